#include <agex/io/atomic_file.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace agex
{
void
writeFileAtomic (const std::string &path, const std::string &bytes)
{
  const fs::path target (path);
  const fs::path dir = target.has_parent_path () ? target.parent_path () : fs::path (".");
  std::string tmpl = (dir / ("." + target.filename ().string () + ".tmp-XXXXXX")).string ();
  const int fd = ::mkstemp (tmpl.data ());
  if (fd < 0)
    throw std::runtime_error (path + ": cannot create a temporary file in '" + dir.string () +
                              "': " + std::strerror (errno));
  std::size_t written = 0;
  while (written < bytes.size ())
  {
    const ssize_t n = ::write (fd, bytes.data () + written, bytes.size () - written);
    if (n < 0)
    {
      if (errno == EINTR)
        continue;
      const int err = errno;
      ::close (fd);
      ::unlink (tmpl.c_str ());
      throw std::runtime_error (path + ": write failed: " + std::strerror (err));
    }
    written += static_cast<std::size_t> (n);
  }
  // mkstemp creates 0600; outputs should be readable like any other file.
  ::fchmod (fd, 0644);
  if (::fsync (fd) != 0 || ::close (fd) != 0)
  {
    const int err = errno;
    ::unlink (tmpl.c_str ());
    throw std::runtime_error (path + ": cannot flush: " + std::strerror (err));
  }
  if (std::rename (tmpl.c_str (), path.c_str ()) != 0)
  {
    const int err = errno;
    ::unlink (tmpl.c_str ());
    throw std::runtime_error (path + ": cannot move the finished file into place: " + std::strerror (err));
  }
}

void
checkOutputIsNotInput (const std::string &output, const std::vector<std::string> &inputs)
{
  InputFiles (inputs).checkOutput (output);
}

InputFiles::InputFiles (const std::vector<std::string> &paths)
{
  for (const auto &path : paths)
    add (path);
}

void
InputFiles::add (const std::string &path)
{
  std::error_code ec;
  // Absolute first: of a path none of whose parts exist yet, weakly_canonical keeps it relative.
  const fs::path p = fs::weakly_canonical (fs::absolute (path, ec), ec);
  if (ec || p.empty ())
    return;
  files_.insert (p);
  for (fs::path a = p.parent_path (); !a.empty () && folders_.insert (a).second; a = a.parent_path ())
    if (a == a.parent_path ())
      break;
}

void
InputFiles::addTree (const std::string &directory)
{
  std::error_code ec;
  const fs::path p = fs::weakly_canonical (fs::absolute (directory, ec), ec);
  if (ec || p.empty ())
    return;
  add (directory);
  trees_.insert (p);
}

void
InputFiles::checkOutput (const std::string &output) const
{
  std::error_code ec;
  const fs::path out = fs::weakly_canonical (fs::absolute (output, ec), ec);
  if (ec)
    return;
  if (files_.count (out))
    throw std::runtime_error (output + ": output would overwrite an input file; choose another path");
  // A directory output replaced with --force would take its contents with it.
  if (folders_.count (out))
    throw std::runtime_error (output + ": output would replace a directory that holds an input file; choose another path");
  for (fs::path a = out.parent_path (); !a.empty (); a = a.parent_path ())
  {
    if (trees_.count (a))
      throw std::runtime_error (output + ": output would land inside the input dataset " + a.string () +
                                "; write it elsewhere");
    if (a == a.parent_path ())
      break;
  }
}
}  // namespace agex

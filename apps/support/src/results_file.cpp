#include <agex/apps/results_file.h>

#include <agex/io/input_file.h>

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace agex
{
namespace apps
{
namespace
{
bool
sameFile (const struct stat &a, const struct stat &b)
{
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

/** Writes all of bytes at the end (the descriptor is O_APPEND). */
bool
writeAll (int fd, const std::string &bytes)
{
  for (std::size_t done = 0; done < bytes.size ();)
  {
    const ssize_t n = ::write (fd, bytes.data () + done, bytes.size () - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    done += static_cast<std::size_t> (n);
  }
  return true;
}
}  // namespace

ResultsFile::ResultsFile (const std::string &path, const std::string &app) : path_ (path), app_ (app)
{
  auto fail = [&] (const std::string &why) { throw std::runtime_error (path_ + ": " + why); };
  // Open, lock, then check that the path still names what was locked: another run may have
  // removed the file (its own empty one) between our open and our lock.
  for (int attempt = 0; fd_ < 0; ++attempt)
  {
    if (attempt == 10)
      fail ("keeps being replaced while it is opened; is another run removing it?");
    const std::string problem = notARegularFile (path_);
    if (!problem.empty ())
      fail (problem + "; --json takes a file");
    // O_NONBLOCK: should a FIFO appear here after the check, opening it must not hang.
    int fd = ::open (path_.c_str (), O_RDWR | O_APPEND | O_CREAT | O_EXCL | O_CLOEXEC | O_NONBLOCK, 0644);
    created_ = fd >= 0;
    if (fd < 0 && errno == EEXIST)
      fd = ::open (path_.c_str (), O_RDWR | O_APPEND | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0 && errno == ENOENT)
      continue;
    if (fd < 0)
      fail (std::string ("cannot open for appending: ") + std::strerror (errno));
    struct stat opened, named;
    if (::fstat (fd, &opened) != 0 || !S_ISREG (opened.st_mode))
    {
      ::close (fd);
      fail ("is not a regular file; --json takes a file");
    }
    if (::flock (fd, LOCK_EX | LOCK_NB) != 0)
    {
      const int err = errno;
      ::close (fd);
      if (err == EWOULDBLOCK)
        fail ("another " + app_ + " run is writing to this file (it is locked); wait for it to finish, or choose "
              "another --json");
      fail (std::string ("cannot lock: ") + std::strerror (err));
    }
    if (::stat (path_.c_str (), &named) != 0 || !sameFile (opened, named))
    {
      ::close (fd);
      continue;
    }
    ::fcntl (fd, F_SETFL, ::fcntl (fd, F_GETFL) & ~O_NONBLOCK);
    fd_ = fd;
  }
  try
  {
    readBack ();
  }
  catch (...)
  {
    ::close (fd_);  // an existing file that is not ours; one we created is empty and parses
    fd_ = -1;
    throw;
  }
}

namespace
{
/** Whether a torn line begins as agex writes its result lines (keys in sorted order: "batch"
  * in a --shard run, else "detections" first), or is a shorter start of one. */
bool
startsLikeAResult (const std::string &line)
{
  for (const std::string start : {"{\"batch\":{", "{\"detections\":["})
    if (line.compare (0, std::min (line.size (), start.size ()), start, 0, std::min (line.size (), start.size ())) == 0)
      return true;
  return false;
}
}  // namespace

void
ResultsFile::readBack ()
{
  std::string content;
  char buffer[1 << 16];
  for (off_t offset = 0;;)
  {
    const ssize_t n = ::pread (fd_, buffer, sizeof buffer, offset);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      throw std::runtime_error (path_ + ": cannot read: " + std::strerror (errno));
    if (n == 0)
      break;
    content.append (buffer, static_cast<std::size_t> (n));
    offset += n;
  }
  std::size_t line_number = 0;
  for (std::size_t begin = 0; begin < content.size ();)
  {
    std::size_t end = content.find ('\n', begin);
    const bool last = end == std::string::npos;
    if (last)
      end = content.size ();
    const std::string line = content.substr (begin, end - begin);
    ++line_number;
    if (!line.empty ())
    {
      const auto doc = nlohmann::json::parse (line, nullptr, false);
      if (doc.is_object () && doc.contains ("frame") && doc["frame"].is_string ())
      {
        done_.insert (doc["frame"].get<std::string> ());
        if (last && !writeAll (fd_, "\n"))  // the final newline was missing
          throw std::runtime_error (path_ + ": cannot append: " + std::strerror (errno));
      }
      // A line torn by an interrupted run: after whole results, any cut JSON object; alone,
      // only the start of one of ours, never a user's one-line file that is not JSON.
      else if (last && doc.is_discarded () && line[0] == '{' && (!done_.empty () || startsLikeAResult (line)))
      {
        if (::ftruncate (fd_, static_cast<off_t> (begin)) != 0)
          throw std::runtime_error (path_ + ": cannot cut off its torn last line: " + std::strerror (errno));
      }
      else
        throw std::runtime_error (path_ + ": line " + std::to_string (line_number) + " is not a frame result of " +
                                  app_ + "; --json of several frames appends to a JSON-lines file: choose a new "
                                  "path or that of an earlier such run");
    }
    begin = end + 1;
  }
}

void
ResultsFile::append (const std::string &line)
{
  const std::string bytes = line + "\n";
  std::lock_guard<std::mutex> lock (mutex_);
  if (!writeAll (fd_, bytes))
    throw std::runtime_error (path_ + ": write failed: " + std::strerror (errno));
  ++appended_;
}

ResultsFile::~ResultsFile ()
{
  if (fd_ < 0)
    return;
  // Still locked: nobody else can have written to it. Remove it only if it is still ours.
  struct stat opened, named;
  if (created_ && appended_ == 0 && ::fstat (fd_, &opened) == 0 && opened.st_size == 0 &&
      ::stat (path_.c_str (), &named) == 0 && sameFile (opened, named))
    ::unlink (path_.c_str ());
  ::close (fd_);
}
}  // namespace apps
}  // namespace agex

#pragma once
// Shared by the fuzz targets: agex's readers take paths, so each input is written to a
// file (with the extension the reader dispatches on) in a scratch directory of this
// process, reused for every input.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

namespace agex
{
namespace fuzz
{
/** A scratch directory of this process, removed at exit. */
inline const std::string &
scratchDirectory ()
{
  // Never destroyed: the exit handler that removes the directory runs after static
  // destructors of objects constructed later would have run.
  static const std::string *dir = [] {
    const char *tmp = std::getenv ("TMPDIR");
    std::string tmpl = std::string (tmp && *tmp ? tmp : "/tmp") + "/agex-fuzz-XXXXXX";
    if (!::mkdtemp (tmpl.data ()))
      std::abort ();
    auto *path = new std::string (tmpl);
    std::atexit ([] { std::system (("rm -rf '" + scratchDirectory () + "'").c_str ()); });
    return path;
  }();
  return *dir;
}

/** Writes bytes to <scratch>/<name> and returns the path. */
inline std::string
writeInput (const std::string &name, const std::uint8_t *data, std::size_t size)
{
  const std::string path = scratchDirectory () + "/" + name;
  std::ofstream out (path, std::ios::binary | std::ios::trunc);
  out.write (reinterpret_cast<const char *> (data), static_cast<std::streamsize> (size));
  out.close ();
  if (!out)
    std::abort ();
  return path;
}
}  // namespace fuzz
}  // namespace agex

#pragma once
// Every reader of outside input opens regular files only: opening a FIFO blocks until some
// other process writes to it (a run that hangs forever without a word), and a device or
// /dev/zero never ends.

#include <string>

namespace agex
{
/** \brief What path is if it exists but is not a regular file (after following symlinks),
  * e.g. "is a FIFO (named pipe), not a regular file"; "" for a regular file, and for a path
  * that cannot be looked at (missing: the reader's own open says so). One stat(2); the file
  * is never opened. */
std::string notARegularFile (const std::string &path);
}  // namespace agex

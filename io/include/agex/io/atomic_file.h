#pragma once
// Outputs are written atomically: a temporary file in the same directory, then
// rename(2), so a crash or a full disk never leaves a half-written file behind
// and an earlier good output survives a failed run.

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace agex
{
/** \brief Writes bytes to path atomically.
  * \throws std::runtime_error naming the path and the reason on failure */
void writeFileAtomic (const std::string &path, const std::string &bytes);

/** \brief Throws std::runtime_error if output names the same file as any input, or a
  * directory that holds one (so an app never overwrites or replaces what it reads). */
void checkOutputIsNotInput (const std::string &output, const std::vector<std::string> &inputs);

/** \brief The files an app reads, resolved once, so that each of many outputs (one
  * overlay per image of a large dataset) is checked against all of them cheaply. */
class InputFiles
{
public:
  InputFiles () = default;
  explicit InputFiles (const std::vector<std::string> &paths);
  /** Adds a file that is read; paths that cannot be resolved are skipped. */
  void add (const std::string &path);
  /** Adds a directory that is read as a whole (an input dataset): no output may be written
    * anywhere inside it, nor replace it or a directory above it. */
  void addTree (const std::string &directory);
  /** \throws std::runtime_error if output names an input, a directory that holds one, or a
    * path inside a directory added with addTree */
  void checkOutput (const std::string &output) const;

private:
  std::set<std::filesystem::path> files_;
  std::set<std::filesystem::path> folders_;  ///< every directory above an input
  std::set<std::filesystem::path> trees_;    ///< directories no output may enter
};
}  // namespace agex

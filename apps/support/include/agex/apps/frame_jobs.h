#pragma once
// The frames a run over many inputs processes (frame files, directories of frames, agex
// datasets), each named by a canonical identity, and the parallel batch loop that writes one
// JSON line per finished frame.

#include <agex/apps/results_file.h>
#include <agex/io/atomic_file.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct FrameJob
{
  /** The frame's canonical name, the same however the input was spelled and from whichever
    * directory the run was started: "<dataset directory name>/<frame id>" for a frame of an
    * agex dataset (given whole or as one of its frame files), else "<name of the directory
    * holding the file>/<file name>". Resumed runs find their frames by it. */
  std::string name;
  std::string path;  ///< the file to load
};

/** \brief The frames of the inputs, each once, in order (directories sorted by name). read
  * gets every file they come from, and every dataset they belong to as a whole (no output may
  * go inside it). app names the program in messages.
  * \throws std::runtime_error naming the input: no such file or directory, a directory without
  *         frames, two different files with the same canonical name */
std::vector<FrameJob> collectFrameJobs (const std::vector<std::string> &inputs, InputFiles &read,
                                        const std::string &app);

/** \brief Runs process on every job results does not already hold, on up to `threads`
  * threads, appending each returned document as one JSON line as it finishes (to results, or
  * to standard output when results is null). After a frame fails no new frame is started;
  * those in flight finish and are written.
  * \throws std::runtime_error: the first failure, saying that the frames done are kept */
void runFrameBatch (const std::vector<FrameJob> &jobs, ResultsFile *results, int threads,
                    const std::function<nlohmann::json (const FrameJob &)> &process);
}  // namespace apps
}  // namespace agex

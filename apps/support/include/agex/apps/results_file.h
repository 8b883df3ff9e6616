#pragma once
// The JSON-lines results file of a run over many frames (agex_detect --json): one line per
// finished frame, appended as frames finish, so that a killed run keeps what it did and a
// rerun does only the rest.

#include <mutex>
#include <set>
#include <string>

namespace agex
{
namespace apps
{
/** \brief A JSON-lines results file, opened for one run.
  *
  * The file is locked (flock(2), exclusive) from construction to destruction: a second run on
  * the same file, started at the same time or later, is refused at once with a message
  * saying so, instead of both writing every frame. On opening, the lines already there are
  * read back: each must be a JSON object with a string "frame" (a frame's canonical name,
  * see collectFrameJobs), and those frames count as done. Only the last line may be torn (a
  * run killed inside a write): it is cut off in place, and a missing final newline added,
  * before anything is appended. Any other line that is not a frame result means the file is
  * not a results file, and it is left alone.
  *
  * A file this run created and wrote no line to is removed again, so that a run that fails
  * before its first frame leaves no empty results file behind. */
class ResultsFile
{
public:
  /** \brief Opens (creating if missing) and locks path; app names the program in messages.
    * \throws std::runtime_error naming the path: locked by another run, not a regular file,
    *         a line that is not a frame result, or an I/O error */
  ResultsFile (const std::string &path, const std::string &app);
  ~ResultsFile ();
  ResultsFile (const ResultsFile &) = delete;
  ResultsFile &operator= (const ResultsFile &) = delete;

  const std::string &path () const { return path_; }
  const std::string &app () const { return app_; }
  /** Whether the frame was in the file when it was opened. */
  bool contains (const std::string &frame) const { return done_.count (frame) != 0; }
  /** How many frames were in the file when it was opened. */
  std::size_t doneCount () const { return done_.size (); }
  /** Appends one line (the newline is added) with a single write; safe to call from several
    * threads. \throws std::runtime_error if the write fails */
  void append (const std::string &line);

private:
  std::string path_, app_;
  int fd_ = -1;
  bool created_ = false;
  std::set<std::string> done_;
  std::mutex mutex_;
  std::size_t appended_ = 0;

  void readBack ();
};
}  // namespace apps
}  // namespace agex

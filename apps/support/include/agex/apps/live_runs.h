#pragma once
// agex_detect --device: frames processed as a live source (a depth camera, or a replay at a
// set frame rate) delivers them, until it ends or Ctrl-C.

#include <agex/io/frame_io.h>
#include <agex/io/frame_source.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>

namespace agex
{
namespace apps
{
/** A source's frame as loadFrame would have given it (the cloud is shared, not copied). */
Frame liveFrame (const SourceFrame &frame);

/** \brief Runs process on the frames of --device until the source ends or SIGINT/SIGTERM
  * (Ctrl-C) stops it: the frames being processed finish and are written, nothing waits in a
  * queue. device is "openni2" or "openni2:URI" (agex::openOpenNI2), or "replay:PATH"
  * (agex::openFrames at fps frames per second: a directory, dataset, image sequence or file
  * replayed as a camera). Each frame's document gets "sequence" (the source's frame number),
  * "timestamp" (seconds) and "dropped" (frames the source dropped so far because every
  * consumer was busy) and is written as one JSON line, as it finishes, to json_path (appended;
  * ResultsFile: locked, a torn last line repaired) or standard output; threads frames are
  * processed at a time. A summary (frames processed and dropped, seconds, frames per second)
  * goes to standard error. A second Ctrl-C exits at once (status 130).
  * \return 0 when the source ended or was stopped
  * \throws std::runtime_error naming the device: a malformed --device, no device (what was
  *         tried), a frame that failed (the frames before it are written) */
int runLiveDetection (const std::string &device, double fps, const FrameOptions &options, const std::string &json_path,
                      int threads, const std::string &app,
                      const std::function<nlohmann::json (const SourceFrame &)> &process);
}  // namespace apps
}  // namespace agex

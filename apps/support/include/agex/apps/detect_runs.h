#pragma once
// agex_detect's frames: the library's detector (agex::BodyPartDetector) run on one frame and
// its result written as the app's JSON document, overlays and summary lines.

#include <agex/apps/detect_flags.h>
#include <agex/apps/frame_jobs.h>
#include <agex/io/atomic_file.h>
#include <agex/io/frame_source.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace agex
{
namespace apps
{
/** \brief One frame's detections as agex_detect writes them: frame, path, size, detector mode,
  * detections, persons and per-stage milliseconds ("total" from before the frame was loaded).
  * The frame is loaded from job.path with the flags' frame options, or taken from live. The
  * overlay (detections at or above --min-confidence) and the forest's part map are drawn
  * into the Mats given. */
nlohmann::json detectFrame (const FrameJob &job, const LoadedDetector &loaded, const DetectFlags &flags,
                            cv::Mat *overlay = nullptr, cv::Mat *parts_overlay = nullptr,
                            const SourceFrame *live = nullptr);

/** \brief Refuses outputs that would overwrite what is read or are not for this run: --json a
  * JSON document for a single frame (single), else JSON lines; --overlay and --parts-overlay
  * PNGs, and only for a single frame. \throws std::runtime_error naming the flag or path */
void checkDetectOutputs (const DetectFlags &flags, bool single, const InputFiles &read);

/** agex_detect on a single frame: the JSON document to --json (or standard output), the
  * overlays asked for, and the detections at or above --min-confidence on standard error. */
void detectSingleFrame (const FrameJob &job, const LoadedDetector &loaded, const DetectFlags &flags);
}  // namespace apps
}  // namespace agex

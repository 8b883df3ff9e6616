#pragma once
// agex_detect's frames: the library's detector (agex::BodyPartDetector) run on one frame and
// its result written as the app's JSON document, overlays and summary lines.

#include <agex/apps/detect_flags.h>
#include <agex/apps/frame_jobs.h>
#include <agex/io/atomic_file.h>
#include <agex/io/frame_source.h>

#include <pcl/point_types.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <memory>
#include <mutex>
#include <vector>

namespace agex
{
namespace apps
{
/** \brief agex_detect's detectors: one for each thread at work, each kept from frame to frame
  * with its buffers (agex::DepthPipeline refills them in place), as a program processing a
  * stream holds one. A frame takes a detector no other thread uses and gives it back. */
class DetectorPool
{
public:
  explicit DetectorPool (const LoadedDetector &loaded);
  ~DetectorPool ();
  DetectorPool (const DetectorPool &) = delete;
  DetectorPool &operator= (const DetectorPool &) = delete;

  const LoadedDetector &loaded () const { return loaded_; }

  /** fn (detector) with a detector set up from the loaded model, for this call alone. */
  template <typename Fn>
  auto with (Fn &&fn)
  {
    struct Lease
    {
      DetectorPool &pool;
      BodyPartDetector<pcl::PointXYZ> *detector;
      ~Lease () { pool.giveBack (detector); }
    } lease{*this, take ()};
    return fn (*lease.detector);
  }

  /** Detectors made so far: at most one per thread that ran at the same time. */
  std::size_t size () const;

private:
  BodyPartDetector<pcl::PointXYZ> *take ();
  void giveBack (BodyPartDetector<pcl::PointXYZ> *detector);

  const LoadedDetector &loaded_;
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<BodyPartDetector<pcl::PointXYZ>>> all_;
  std::vector<BodyPartDetector<pcl::PointXYZ> *> idle_;
};

/** \brief One frame's detections as agex_detect writes them: frame, path, size, detector mode,
  * detections, persons and per-stage milliseconds ("total" from before the frame was loaded).
  * The frame is loaded from job.path with the flags' frame options, or taken from live, and
  * goes through one of the pool's detectors. The overlay (detections at or above
  * --min-confidence) and the forest's part map are drawn into the Mats given. */
nlohmann::json detectFrame (const FrameJob &job, DetectorPool &detectors, const DetectFlags &flags,
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

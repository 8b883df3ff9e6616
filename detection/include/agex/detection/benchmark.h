#pragma once
// How fast the detector and its stages run on given frames: the depth pipeline stage by stage,
// AGEX with the incremental multi-source Dijkstra against the naive reference (k full runs)
// on the same meshes, and the whole detector over many frames. Frames are in memory first:
// file I/O is not part of what is timed. Single-threaded; the figures themselves belong in
// doc/benchmarks.md, never in code.

#include <agex/detection/body_part_detector.h>
#include <agex/detection/depth_pipeline.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace agex
{
/** Median and 95th percentile of repeated timings, milliseconds. */
struct TimingStats
{
  double median = 0.0, p95 = 0.0;
};

/** \brief The middle sample (the upper of the two middle ones for an even count: a time that
  * was measured, not a mean) and the sample at 95% of the sorted samples; zeros when empty. */
TimingStats summariseTimings (std::vector<double> samples);

/** The depth pipeline and AGEX on one frame (benchmarkDepthPipeline). */
struct DepthPipelineBenchmark
{
  std::size_t meshes = 0, mesh_points = 0;  ///< of the pipeline's result
  std::size_t points = 0;                   ///< AGEX_k points on its meshes
  TimingStats agex_incremental, agex_naive;
  /** Both AGEX modes gave the same points (pixels and geodesic distances, in order). */
  bool identical = false;
  /** Per stage, in the pipeline's order ("total" last), over the runs. */
  std::vector<std::pair<std::string, TimingStats>> pipeline;

  /** Naive over incremental median; 0 when the incremental median is 0. */
  double speedup () const { return agex_incremental.median > 0 ? agex_naive.median / agex_incremental.median : 0.0; }
};

/** \brief Runs the depth pipeline repeat times on cloud, then AGEX_k on the meshes of its
  * result in both modes (incremental and naive, each after one untimed run that allocates
  * its scratch buffers) repeat times each; AGEX keeps every mesh (no minimum size). */
DepthPipelineBenchmark benchmarkDepthPipeline (const pcl::PointCloud<pcl::PointXYZ>::Ptr &cloud,
                                               const DepthPipelineParams &params, int k, int repeat);

/** Sets up a detector to time (model, forest, mode; see BodyPartDetector). */
using DetectorSetup = std::function<void (BodyPartDetector<pcl::PointXYZ> &)>;

/** \brief Milliseconds of one detection: a detector made, set up, given the focal length
  * (fx, fy) and cloud, and run; each stage as the detector times it, then "total" (all of it,
  * the detector's construction included: a first frame's cost). */
std::vector<std::pair<std::string, double>> timeDetection (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud,
                                                           const DetectorSetup &setup, float fx, float fy);

/** \brief Milliseconds of one detection by a detector that is already set up (and may have
  * run on earlier frames, as in a stream): each stage, then "total" (the whole compute ()). */
std::vector<std::pair<std::string, double>> timeDetection (BodyPartDetector<pcl::PointXYZ> &detector,
                                                           const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud);

/** The whole detector over frames (benchmarkDetector). */
struct DetectorBenchmark
{
  /** Per stage, in the detector's order ("total" last): over the frames, of each frame's
    * median over its passes. */
  std::vector<std::pair<std::string, TimingStats>> stages;
  TimingStats total;  ///< the "total" stage
};

/** \brief Times the detector on every frame passes times after one untimed run on the first
  * frame (caches, lazy allocations): one detector for all of them, as a program processing a
  * stream of frames holds it. progress (done, total) is called after each frame.
  * \throws std::invalid_argument when clouds is empty */
DetectorBenchmark benchmarkDetector (const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> &clouds,
                                     const DetectorSetup &setup, float fx, float fy, int passes,
                                     const std::function<void (std::size_t, std::size_t)> &progress = {});

/** The process's resident memory in bytes (Linux: /proc/self/statm), 0 where it cannot be read. */
std::size_t residentBytes ();

/** Resident memory over a long stream (benchmarkMemory), bytes. */
struct MemoryBenchmark
{
  std::size_t frames = 0;
  std::size_t after_first_pass = 0;  ///< after every frame ran once (buffers at their size)
  std::size_t final = 0;  ///< at the end
  /** The largest sample (after the first pass, every interval frames, at the end), not the
    * high-water mark between samples. */
  std::size_t peak = 0;
  /** (frames run, resident bytes) every interval frames, the last at frames. */
  std::vector<std::pair<std::size_t, std::size_t>> samples;
  /** final - after_first_pass (negative when memory was returned). */
  long long growth () const { return static_cast<long long> (final) - static_cast<long long> (after_first_pass); }
};

/** \brief Runs one detector over frames cyclically (frame i % clouds.size ()) for the given
  * number of frames, as a program processing a stream holds it, and samples residentBytes ()
  * after the first pass over the frames (or after all of them, when frames <= clouds.size ())
  * and every interval frames: memory that grows with the frames run is a leak or an unbounded
  * cache. The allocator may still settle in the first passes (glibc moves its threshold for
  * returning large blocks the first time one is freed); a trend over the samples says more
  * than one difference. progress (done, total) every interval.
  * \throws std::invalid_argument when clouds is empty, or frames or interval is 0 */
MemoryBenchmark benchmarkMemory (const std::vector<pcl::PointCloud<pcl::PointXYZ>::ConstPtr> &clouds,
                                 const DetectorSetup &setup, float fx, float fy, std::size_t frames,
                                 std::size_t interval,
                                 const std::function<void (std::size_t, std::size_t)> &progress = {});
}  // namespace agex

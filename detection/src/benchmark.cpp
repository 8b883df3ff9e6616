#include <agex/detection/benchmark.h>

#include <agex/common/statistics.h>
#include <agex/keypoints/agex_keypoint.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <stdexcept>

namespace agex
{
namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Clock = std::chrono::steady_clock;

/** Times one AGEX mode on fixed meshes; returns per-run milliseconds and the points. */
std::vector<double>
timeAgex (const Cloud::Ptr &cloud, const DepthPipelineResult &prepared, const DepthPipelineParams &params, int k,
          bool naive, int repeat, pcl::PointCloud<InterestPoint> &points)
{
  using Keypoint = AGEXKeypoint<pcl::PointXYZ, InterestPoint>;
  Keypoint agex;
  agex.setInputCloud (cloud);
  agex.setMeshes (prepared.meshes);
  agex.setPointsPerMesh (k);
  agex.setDeltaConnected (params.delta_connected);
  agex.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
  agex.setDeltaOrient (params.delta_orient);
  agex.setMinMeshSize (1);
  agex.setMode (naive ? Keypoint::Mode::Naive : Keypoint::Mode::Incremental);
  std::vector<double> ms;
  agex.compute (points);  // warm-up: scratch buffers allocated once
  for (int r = 0; r < repeat; ++r)
  {
    const auto start = Clock::now ();
    agex.compute (points);
    ms.push_back (msSince (start));
  }
  return ms;
}
}  // namespace

TimingStats
summariseTimings (std::vector<double> samples)
{
  TimingStats s;
  if (samples.empty ())
    return s;
  std::sort (samples.begin (), samples.end ());
  s.median = samples[samples.size () / 2];
  s.p95 = samples[std::min (samples.size () - 1, static_cast<std::size_t> (0.95 * samples.size ()))];
  return s;
}

DepthPipelineBenchmark
benchmarkDepthPipeline (const Cloud::Ptr &cloud, const DepthPipelineParams &params, int k, int repeat)
{
  std::map<std::string, std::vector<double>> stage_ms;
  DepthPipelineResult prepared;
  // One pipeline for every run, as a program processing a stream holds it.
  DepthPipeline<pcl::PointXYZ> pipeline;
  pipeline.setParams (params);
  pipeline.setInputCloud (cloud);
  for (int r = 0; r < repeat; ++r)
  {
    pipeline.compute (prepared);
    for (const auto &[stage, ms] : prepared.ms)
      stage_ms[stage].push_back (ms);
  }
  DepthPipelineBenchmark bench;
  bench.meshes = prepared.meshes.size ();
  for (const auto &m : prepared.meshes)
    bench.mesh_points += m.indices.size ();

  pcl::PointCloud<InterestPoint> incremental, naive;
  bench.agex_incremental = summariseTimings (timeAgex (prepared.filtered, prepared, params, k, false, repeat, incremental));
  bench.agex_naive = summariseTimings (timeAgex (prepared.filtered, prepared, params, k, true, repeat, naive));
  bench.points = incremental.size ();
  bench.identical = incremental.size () == naive.size ();
  for (std::size_t i = 0; bench.identical && i < incremental.size (); ++i)
    bench.identical = incremental[i].u == naive[i].u && incremental[i].v == naive[i].v &&
                      incremental[i].geodesic_distance == naive[i].geodesic_distance;
  for (const auto &stage : prepared.ms)
    bench.pipeline.emplace_back (stage.first, summariseTimings (stage_ms[stage.first]));
  return bench;
}

std::vector<std::pair<std::string, double>>
timeDetection (BodyPartDetector<pcl::PointXYZ> &detector, const Cloud::ConstPtr &cloud)
{
  const auto start = Clock::now ();
  detector.setInputCloud (cloud);
  std::vector<BodyPartDetection> detections;
  detector.compute (detections);
  const double total = msSince (start);
  std::vector<std::pair<std::string, double>> ms;
  for (const auto &stage : detector.getIntermediate ().ms)
    if (stage.first != "total")
      ms.push_back (stage);
  ms.emplace_back ("total", total);
  return ms;
}

std::vector<std::pair<std::string, double>>
timeDetection (const Cloud::ConstPtr &cloud, const DetectorSetup &setup, float fx, float fy)
{
  const auto start = Clock::now ();
  BodyPartDetector<pcl::PointXYZ> detector;
  setup (detector);
  detector.setFocalLength (fx, fy);
  auto ms = timeDetection (detector, cloud);
  ms.back ().second = msSince (start);
  return ms;
}

DetectorBenchmark
benchmarkDetector (const std::vector<Cloud::ConstPtr> &clouds, const DetectorSetup &setup, float fx, float fy,
                   int passes, const std::function<void (std::size_t, std::size_t)> &progress)
{
  if (clouds.empty ())
    throw std::invalid_argument ("benchmarkDetector: no frames");
  // One detector for every frame, as a program processing a stream holds it.
  BodyPartDetector<pcl::PointXYZ> detector;
  setup (detector);
  detector.setFocalLength (fx, fy);
  timeDetection (detector, clouds.front ());  // warm-up: caches, lazy allocations
  std::vector<std::string> stage_order;
  std::map<std::string, std::vector<double>> per_frame;  // stage -> one median per frame
  for (std::size_t f = 0; f < clouds.size (); ++f)
  {
    std::map<std::string, std::vector<double>> runs;
    for (int p = 0; p < passes; ++p)
      for (const auto &[stage, ms] : timeDetection (detector, clouds[f]))
      {
        if (f == 0 && p == 0)
          stage_order.push_back (stage);
        runs[stage].push_back (ms);
      }
    for (auto &[stage, samples] : runs)
      per_frame[stage].push_back (summariseTimings (samples).median);
    if (progress)
      progress (f + 1, clouds.size ());
  }
  DetectorBenchmark bench;
  for (const auto &stage : stage_order)
    bench.stages.emplace_back (stage, summariseTimings (per_frame[stage]));
  bench.total = summariseTimings (per_frame["total"]);
  return bench;
}

std::size_t
residentBytes ()
{
  // statm: total program size, then resident pages.
  std::ifstream statm ("/proc/self/statm");
  std::size_t size = 0, resident = 0;
  if (!(statm >> size >> resident))
    return 0;
  const long page = sysconf (_SC_PAGESIZE);
  return page > 0 ? resident * static_cast<std::size_t> (page) : 0;
}

MemoryBenchmark
benchmarkMemory (const std::vector<Cloud::ConstPtr> &clouds, const DetectorSetup &setup, float fx, float fy,
                 std::size_t frames, std::size_t interval, const std::function<void (std::size_t, std::size_t)> &progress)
{
  if (clouds.empty ())
    throw std::invalid_argument ("benchmarkMemory: no frames");
  if (interval == 0 || frames == 0)
    throw std::invalid_argument ("benchmarkMemory: the frames to run and the sampling interval must be at least one");
  BodyPartDetector<pcl::PointXYZ> detector;
  setup (detector);
  detector.setFocalLength (fx, fy);
  std::vector<BodyPartDetection> detections;
  MemoryBenchmark bench;
  bench.frames = frames;
  for (std::size_t f = 0; f < frames; ++f)
  {
    detector.setInputCloud (clouds[f % clouds.size ()]);
    detector.compute (detections);
    const std::size_t done = f + 1;
    if (done == std::min (frames, clouds.size ()))
      bench.after_first_pass = residentBytes ();
    if (done % interval == 0 || done == frames)
    {
      const std::size_t rss = residentBytes ();
      bench.samples.emplace_back (done, rss);
      bench.peak = std::max (bench.peak, rss);
      if (progress)
        progress (done, frames);
    }
  }
  bench.final = bench.samples.empty () ? residentBytes () : bench.samples.back ().second;
  bench.peak = std::max ({bench.peak, bench.final, bench.after_first_pass});
  return bench;
}
}  // namespace agex

#include <agex/apps/bench_runs.h>

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/detection/benchmark.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

namespace agex
{
namespace apps
{
OutputRecogniser
benchReportRecogniser ()
{
  return [frames = jsonReportWith ({"k", "repeat", "frames"}), dataset = jsonReportWith ({"dataset", "detector_mode"}),
          compared = jsonReportWith ({"compare_with", "rounds"})] (const std::string &path) {
    const std::string why = frames (path);
    return why.empty () || dataset (path).empty () || compared (path).empty () ? std::string () : why;
  };
}

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

nlohmann::json
statsJson (const TimingStats &s)
{
  return {{"median", s.median}, {"p95", s.p95}};
}

nlohmann::json
benchView (const std::string &label, const Cloud::Ptr &cloud, const DepthPipelineParams &params, int k, int repeat)
{
  const DepthPipelineBenchmark bench = benchmarkDepthPipeline (cloud, params, k, repeat);
  std::printf ("  %-9s %4ux%-4u %zu meshes, %zu mesh points, %zu points\n", label.c_str (), cloud->width,
               cloud->height, bench.meshes, bench.mesh_points, bench.points);
  std::printf ("    AGEX_%d incremental  %8.3f ms median  %8.3f ms p95\n", k, bench.agex_incremental.median,
               bench.agex_incremental.p95);
  std::printf ("    AGEX_%d naive        %8.3f ms median  %8.3f ms p95\n", k, bench.agex_naive.median,
               bench.agex_naive.p95);
  std::printf ("    speed-up %.1fx, results %s\n", bench.speedup (), bench.identical ? "identical" : "DIFFERENT");
  nlohmann::json stages = nlohmann::json::object ();
  std::printf ("    pipeline (k=%d):", params.k);
  for (const auto &[stage, s] : bench.pipeline)
  {
    stages[stage] = statsJson (s);
    std::printf (" %s %.2f", stage.c_str (), s.median);
  }
  std::printf (" ms (medians)\n");

  return {{"width", cloud->width},
          {"height", cloud->height},
          {"meshes", bench.meshes},
          {"mesh_points", bench.mesh_points},
          {"k", k},
          {"agex_incremental_ms", statsJson (bench.agex_incremental)},
          {"agex_naive_ms", statsJson (bench.agex_naive)},
          {"speedup", bench.speedup ()},
          {"identical", bench.identical},
          {"pipeline_ms", stages}};
}
}  // namespace

nlohmann::json
benchFrames (const std::vector<std::string> &inputs, const FrameOptions &frame_options, const DepthPipelineParams &params,
             int k, int repeat, bool portrait)
{
  nlohmann::json doc;
  doc["k"] = k;
  doc["repeat"] = repeat;
  doc["frames"] = nlohmann::json::array ();
  for (const auto &input : inputs)
  {
    const Frame frame = loadFrame (input, frame_options);
    std::printf ("%s\n", input.c_str ());
    nlohmann::json entry;
    entry["frame"] = input;
    entry["full"] = benchView ("full", frame.cloud, params, k, repeat);
    if (portrait && frame.cloud->width == 640 && frame.cloud->height == 480)
    {
      Cloud::Ptr view (new Cloud);
      applyView (*frame.cloud, bonnPortraitView (), *view);
      entry["portrait"] = benchView ("portrait", view, params, k, repeat);
    }
    doc["frames"].push_back (entry);
  }
  return doc;
}

nlohmann::json
benchDataset (const std::string &spec, bool keyframes_only, const LoadedDetector &loaded, int passes, int jobs,
              std::size_t memory_frames)
{
  const DatasetSelection selection = selectDataset (spec, keyframes_only);
  if (selection.frame_ids.empty ())
    throw std::runtime_error (spec + ": no frames selected");
  const auto &intr = selection.dataset.info ().intrinsics;
  const float fx = static_cast<float> (intr.fx), fy = static_cast<float> (intr.fy);

  // Frames are loaded first: file I/O is not part of the detector.
  std::vector<Cloud::ConstPtr> clouds;
  for (const auto &id : selection.frame_ids)
    clouds.push_back (selection.dataset.loadFrame (id));

  const DetectorSetup setup = [&loaded] (BodyPartDetector<pcl::PointXYZ> &detector) { loaded.configure (detector); };
  Progress progress ("frames", clouds.size ());
  const DetectorBenchmark bench = benchmarkDetector (clouds, setup, fx, fy, passes,
                                                     [&] (std::size_t done, std::size_t) { progress.step (done); });
  nlohmann::json stages = nlohmann::json::object ();
  std::printf ("%s: %zu frames %ux%u, %d pass%s each, one thread\n", spec.c_str (), clouds.size (),
               clouds.front ()->width, clouds.front ()->height, passes, passes == 1 ? "" : "es");
  for (const auto &[stage, s] : bench.stages)
  {
    std::printf ("  %-14s %8.3f ms median  %8.3f ms p95\n", stage.c_str (), s.median, s.p95);
    if (stage != "total")
      stages[stage] = statsJson (s);
  }

  // Throughput: every frame once, spread over the threads.
  std::atomic<std::size_t> next{0};
  const auto start = std::chrono::steady_clock::now ();
  jobs = runWorkers (jobs, clouds.size (), [&] () {
    BodyPartDetector<pcl::PointXYZ> detector;  // one per thread, for all its frames
    setup (detector);
    detector.setFocalLength (fx, fy);
    for (std::size_t i = next++; i < clouds.size (); i = next++)
      timeDetection (detector, clouds[i]);
  });
  const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
  const double fps = seconds > 0 ? clouds.size () / seconds : 0.0;
  std::printf ("  throughput     %8.1f frames/s with %d job%s (%u hardware threads)\n", fps, jobs,
               jobs == 1 ? "" : "s", std::thread::hardware_concurrency ());

  nlohmann::json doc = {{"dataset", spec},
          {"model", loaded.files.front ()},
          {"detector_mode", loaded.mode_name},
          {"forest", loaded.forest_file},
          {"forest_stride", loaded.forest_stride},
          {"cascade_min_confidence", loaded.cascade_min_confidence},
          {"cascade_miss_rate", loaded.cascade_miss_rate},
          {"tip_radius", loaded.tip_refinement.radius},
          {"tip_min_confidence", loaded.tip_refinement.min_relative_confidence},
          {"window_model", loaded.window_file},
          {"window_weight", loaded.window_model ? loaded.window_weight : 0.f},
          {"frames", clouds.size ()},
          {"width", clouds.front ()->width},
          {"height", clouds.front ()->height},
          {"passes", passes},
          {"ms_per_frame", statsJson (bench.total)},
          {"stages", stages},
          {"throughput", {{"jobs", jobs}, {"frames_per_second", fps}}}};
  if (memory_frames > 0)
  {
    if (memory_frames < 2 * clouds.size ())
      throw std::runtime_error ("--memory-frames " + std::to_string (memory_frames) + " must be at least twice the " +
                                std::to_string (clouds.size ()) +
                                " selected frames: growth is measured after a first pass over them");
    // About twenty samples, so that a slow growth shows as a trend, not one number.
    const std::size_t interval = std::max<std::size_t> (1, memory_frames / 20);
    Progress memory_progress ("memory run frames", memory_frames);
    const MemoryBenchmark memory = benchmarkMemory (
        clouds, setup, fx, fy, memory_frames, interval, [&] (std::size_t done, std::size_t) { memory_progress.step (done); });
    constexpr double kMiB = 1024.0 * 1024.0;
    if (memory.final == 0)
      std::printf ("  memory         unavailable (no /proc/self/statm to read)\n");
    else
      std::printf ("  memory         %.1f MiB after the first pass, %.1f MiB after %zu frames (growth %+.1f MiB, peak "
                 "%.1f MiB)\n",
                 memory.after_first_pass / kMiB, memory.final / kMiB, memory.frames, memory.growth () / kMiB,
                 memory.peak / kMiB);
    nlohmann::json samples = nlohmann::json::array ();
    for (const auto &[frames, bytes] : memory.samples)
      samples.push_back ({{"frames", frames}, {"resident_bytes", bytes}});
    doc["memory"] = {{"frames", memory.frames},
                     {"after_first_pass_bytes", memory.after_first_pass},
                     {"final_bytes", memory.final},
                     {"peak_bytes", memory.peak},
                     {"growth_bytes", memory.growth ()},
                     {"samples", samples}};
  }
  return doc;
}
}  // namespace apps
}  // namespace agex

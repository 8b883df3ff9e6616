// agex_bench: how fast is agex?
//   agex_bench [INPUT...]: for each frame, at full resolution and in the 144x176
//     portrait view of the source paper, times AGEX_k with the incremental multi-source
//     Dijkstra and with the naive k-full-runs reference on the same meshes, and the depth
//     pipeline stage by stage. Single-threaded.
//   agex_bench --dataset DIR: the whole detector (pipeline, patches, classifier) on every
//     frame of a dataset, stage by stage, on one core; then frames per second with --jobs.

#include <agex/apps/command_line.h>
#include <agex/apps/detector_flags.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/apps/output.h>
#include <agex/detection/body_part_detector.h>
#include <agex/io/atomic_file.h>
#include <agex/io/frame_io.h>
#include <agex/keypoints/agex_keypoint.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <thread>

namespace po = boost::program_options;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Clock = std::chrono::steady_clock;

namespace
{
struct Stats
{
  double median = 0.0, p95 = 0.0;
};

Stats
summarise (std::vector<double> samples)
{
  Stats s;
  if (samples.empty ())
    return s;
  std::sort (samples.begin (), samples.end ());
  s.median = samples[samples.size () / 2];
  s.p95 = samples[std::min (samples.size () - 1, static_cast<std::size_t> (0.95 * samples.size ()))];
  return s;
}

nlohmann::json
statsJson (const Stats &s)
{
  return {{"median", s.median}, {"p95", s.p95}};
}

/** Times one AGEX mode on fixed meshes; returns per-run milliseconds and the points. */
std::vector<double>
timeAgex (const Cloud::Ptr &cloud, const agex::DepthPipelineResult &prepared, const agex::DepthPipelineParams &params,
          int k, bool naive, int repeat, pcl::PointCloud<agex::InterestPoint> &points)
{
  using Keypoint = agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint>;
  Keypoint agex;
  agex.setInputCloud (cloud);
  agex.setMeshes (prepared.meshes);
  agex.setPointsPerMesh (k);
  agex.setDeltaConnected (params.delta_connected);
  agex.setDeltaOrient (params.delta_orient);
  agex.setMinMeshSize (1);
  agex.setMode (naive ? Keypoint::Mode::Naive : Keypoint::Mode::Incremental);
  std::vector<double> ms;
  agex.compute (points);  // warm-up: scratch buffers allocated once
  for (int r = 0; r < repeat; ++r)
  {
    const auto start = Clock::now ();
    agex.compute (points);
    ms.push_back (std::chrono::duration<double, std::milli> (Clock::now () - start).count ());
  }
  return ms;
}

nlohmann::json
benchView (const std::string &label, const Cloud::Ptr &cloud, const agex::DepthPipelineParams &params, int k,
           int repeat)
{
  // The whole pipeline, stage by stage.
  std::map<std::string, std::vector<double>> stage_ms;
  agex::DepthPipelineResult prepared;
  for (int r = 0; r < repeat; ++r)
  {
    prepared = agex::runDepthPipeline (cloud, params);
    for (const auto &[stage, ms] : prepared.ms)
      stage_ms[stage].push_back (ms);
  }
  std::size_t mesh_points = 0;
  for (const auto &m : prepared.meshes)
    mesh_points += m.indices.size ();

  pcl::PointCloud<agex::InterestPoint> incremental_points, naive_points;
  const Stats incremental = summarise (timeAgex (prepared.filtered, prepared, params, k, false, repeat, incremental_points));
  const Stats naive = summarise (timeAgex (prepared.filtered, prepared, params, k, true, repeat, naive_points));
  bool identical = incremental_points.size () == naive_points.size ();
  for (std::size_t i = 0; identical && i < incremental_points.size (); ++i)
    identical = incremental_points[i].u == naive_points[i].u && incremental_points[i].v == naive_points[i].v &&
                incremental_points[i].geodesic_distance == naive_points[i].geodesic_distance;

  std::printf ("  %-9s %4ux%-4u %zu meshes, %zu mesh points, %zu points\n", label.c_str (), cloud->width,
               cloud->height, prepared.meshes.size (), mesh_points, incremental_points.size ());
  std::printf ("    AGEX_%d incremental  %8.3f ms median  %8.3f ms p95\n", k, incremental.median, incremental.p95);
  std::printf ("    AGEX_%d naive        %8.3f ms median  %8.3f ms p95\n", k, naive.median, naive.p95);
  std::printf ("    speed-up %.1fx, results %s\n", incremental.median > 0 ? naive.median / incremental.median : 0.0,
               identical ? "identical" : "DIFFERENT");
  nlohmann::json stages = nlohmann::json::object ();
  std::printf ("    pipeline (k=%d):", params.k);
  for (const auto &stage : prepared.ms)
  {
    const Stats s = summarise (stage_ms[stage.first]);
    stages[stage.first] = statsJson (s);
    std::printf (" %s %.2f", stage.first.c_str (), s.median);
  }
  std::printf (" ms (medians)\n");

  return {{"width", cloud->width},
          {"height", cloud->height},
          {"meshes", prepared.meshes.size ()},
          {"mesh_points", mesh_points},
          {"k", k},
          {"agex_incremental_ms", statsJson (incremental)},
          {"agex_naive_ms", statsJson (naive)},
          {"speedup", incremental.median > 0 ? naive.median / incremental.median : 0.0},
          {"identical", identical},
          {"pipeline_ms", stages}};
}

/** Milliseconds of each detector stage on one frame, the cloud already in memory. */
std::vector<std::pair<std::string, double>>
timeDetector (const Cloud::ConstPtr &cloud, const agex::apps::LoadedDetector &loaded, float fx, float fy)
{
  const auto start = Clock::now ();
  agex::BodyPartDetector<pcl::PointXYZ> detector;
  loaded.configure (detector);
  detector.setFocalLength (fx, fy);
  detector.setInputCloud (cloud);
  std::vector<agex::BodyPartDetection> detections;
  detector.compute (detections);
  const double total = std::chrono::duration<double, std::milli> (Clock::now () - start).count ();
  std::vector<std::pair<std::string, double>> ms;
  for (const auto &stage : detector.getIntermediate ().ms)
    if (stage.first != "total")
      ms.push_back (stage);
  ms.emplace_back ("total", total);
  return ms;
}

/** The detector over a dataset: per-stage ms (median over passes per frame, then median and
  * 95th percentile over frames) on one thread, then throughput with `jobs` threads. */
nlohmann::json
benchDataset (const std::string &spec, bool keyframes_only, const agex::apps::LoadedDetector &loaded, int passes,
              int jobs)
{
  const agex::apps::DatasetSelection selection = agex::apps::selectDataset (spec, keyframes_only);
  if (selection.frame_ids.empty ())
    throw std::runtime_error (spec + ": no frames selected");
  const auto &intr = selection.dataset.info ().intrinsics;
  const float fx = static_cast<float> (intr.fx), fy = static_cast<float> (intr.fy);

  // Frames are loaded first: file I/O is not part of the detector.
  std::vector<Cloud::ConstPtr> clouds;
  for (const auto &id : selection.frame_ids)
    clouds.push_back (selection.dataset.loadFrame (id));

  timeDetector (clouds.front (), loaded, fx, fy);  // warm-up: caches, lazy allocations
  std::vector<std::string> stage_order;
  std::map<std::string, std::vector<double>> per_frame;  // stage -> one median per frame
  agex::apps::Progress progress ("frames", clouds.size ());
  for (std::size_t f = 0; f < clouds.size (); ++f)
  {
    std::map<std::string, std::vector<double>> runs;
    for (int p = 0; p < passes; ++p)
      for (const auto &[stage, ms] : timeDetector (clouds[f], loaded, fx, fy))
      {
        if (f == 0 && p == 0)
          stage_order.push_back (stage);
        runs[stage].push_back (ms);
      }
    for (auto &[stage, samples] : runs)
      per_frame[stage].push_back (summarise (samples).median);
    progress.step (f + 1);
  }

  nlohmann::json stages = nlohmann::json::object ();
  std::printf ("%s: %zu frames %ux%u, %d pass%s each, one thread\n", spec.c_str (), clouds.size (),
               clouds.front ()->width, clouds.front ()->height, passes, passes == 1 ? "" : "es");
  for (const auto &stage : stage_order)
  {
    const Stats s = summarise (per_frame[stage]);
    std::printf ("  %-14s %8.3f ms median  %8.3f ms p95\n", stage.c_str (), s.median, s.p95);
    if (stage != "total")
      stages[stage] = statsJson (s);
  }
  const Stats total = summarise (per_frame["total"]);

  // Throughput: every frame once, spread over the threads.
  std::atomic<std::size_t> next{0};
  const auto start = Clock::now ();
  jobs = agex::apps::runWorkers (jobs, clouds.size (), [&] () {
    for (std::size_t i = next++; i < clouds.size (); i = next++)
      timeDetector (clouds[i], loaded, fx, fy);
  });
  const double seconds = std::chrono::duration<double> (Clock::now () - start).count ();
  const double fps = seconds > 0 ? clouds.size () / seconds : 0.0;
  std::printf ("  throughput     %8.1f frames/s with %d job%s (%u hardware threads)\n", fps, jobs,
               jobs == 1 ? "" : "s", std::thread::hardware_concurrency ());

  return {{"dataset", spec},
          {"model", loaded.files.front ()},
          {"detector_mode", loaded.mode_name},
          {"forest", loaded.forest ? loaded.files.back () : std::string ()},
          {"forest_stride", loaded.forest_stride},
          {"frames", clouds.size ()},
          {"width", clouds.front ()->width},
          {"height", clouds.front ()->height},
          {"passes", passes},
          {"ms_per_frame", statsJson (total)},
          {"stages", stages},
          {"throughput", {{"jobs", jobs}, {"frames_per_second", fps}}}};
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  agex::DepthPipelineParams params;
  std::vector<std::string> vector_flags, inputs;
  std::string json_path, dataset_spec;
  agex::apps::DetectorChoice choice;
  int k = 20, repeat = 30, passes = 3, jobs = static_cast<int> (std::max (1u, std::thread::hardware_concurrency ()));
  bool no_portrait = false, keyframes_only = false;

  po::options_description general ("agex_bench [INPUT...] [options]\n"
                                    "agex_bench --dataset DIR[@SEQ,...] [--model MODEL] [--jobs N] [--json FILE]\n"
                                    "Times AGEX (incremental vs naive) and the depth pipeline per frame, or the whole\n"
                                    "detector over a dataset");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&dataset_spec), "time the detector on this dataset's frames (DIR or DIR@1,2,...)")
    ("keyframes", po::bool_switch (&keyframes_only), "with --dataset: keyframes only")
    ("passes", po::value (&passes)->default_value (passes), "with --dataset: timed runs per frame")
    ("jobs", po::value (&jobs)->default_value (jobs), "with --dataset: threads for the throughput run")
    ("input", po::value (&inputs)->multitoken (), "frame files (default: the bundled Bonn frame)")
    ("bench-k", po::value (&k)->default_value (k), "k for the incremental vs naive comparison")
    ("repeat", po::value (&repeat)->default_value (repeat), "timed runs per measurement")
    ("no-portrait", po::bool_switch (&no_portrait), "skip the 144x176 portrait view of 640x480 frames")
    ("json", po::value (&json_path), "write the figures as JSON here");
  po::options_description all;
  all.add (general).add (agex::apps::detectorOptionsDescription (choice, AGEX_BUNDLED_MODEL))
     .add (agex::apps::frameOptionsDescription (frame_options))
     .add (agex::apps::pipelineOptionsDescription (params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", -1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, params);
    if (k < 1 || repeat < 1 || passes < 1 || jobs < 1)
      throw std::runtime_error ("--bench-k, --repeat, --passes and --jobs must be at least 1");
    if (k > 1000)
      throw std::runtime_error ("--bench-k must be at most 1000 (the naive reference runs a full Dijkstra per point)");
    if (!dataset_spec.empty ())
    {
      if (!inputs.empty ())
        throw std::runtime_error ("give either frame files or --dataset, not both");
      if (!json_path.empty ())
      {
        agex::InputFiles read (agex::apps::datasetFiles (agex::apps::selectDataset (dataset_spec, false).dataset));
        read.add (choice.model);
        read.checkOutput (json_path);
      }
      const nlohmann::json doc = benchDataset (dataset_spec, keyframes_only, agex::apps::loadDetector (choice), passes,
                                               jobs);
      if (!json_path.empty ())
        agex::apps::writeJson (json_path, doc);
      return 0;
    }
    if (inputs.empty ())
      inputs.push_back (AGEX_BUNDLED_FRAME);
    if (!json_path.empty ())
    {
      std::vector<std::string> read = inputs;
      read.push_back (choice.model);
      agex::checkOutputIsNotInput (json_path, read);
    }

    nlohmann::json doc;
    doc["k"] = k;
    doc["repeat"] = repeat;
    doc["frames"] = nlohmann::json::array ();
    for (const auto &input : inputs)
    {
      const agex::Frame frame = agex::loadFrame (input, frame_options);
      std::printf ("%s\n", input.c_str ());
      nlohmann::json entry;
      entry["frame"] = input;
      entry["full"] = benchView ("full", frame.cloud, params, k, repeat);
      if (!no_portrait && frame.cloud->width == 640 && frame.cloud->height == 480)
      {
        Cloud::Ptr portrait (new Cloud);
        agex::applyView (*frame.cloud, agex::bonnPortraitView (), *portrait);
        entry["portrait"] = benchView ("portrait", portrait, params, k, repeat);
      }
      doc["frames"].push_back (entry);
    }
    if (!json_path.empty ())
      agex::apps::writeJson (json_path, doc);
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_bench: error: " << e.what () << "\n";
    return 1;
  }
}

// agex_bench: how fast is AGEX? For each frame, at full resolution and in the
// 144x176 portrait view of the source paper, it times AGEX_k with the incremental
// multi-source Dijkstra and with the naive k-full-runs reference on the same
// meshes, and the whole depth pipeline stage by stage. Single-threaded.

#include <agex/apps/command_line.h>
#include <agex/apps/depth_pipeline.h>
#include <agex/apps/output.h>
#include <agex/common/atomic_file.h>
#include <agex/common/frame_io.h>
#include <agex/keypoints/agex_keypoint.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>

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
timeAgex (const Cloud::Ptr &cloud, const agex::apps::PipelineResult &prepared, const agex::apps::PipelineParams &params,
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
benchView (const std::string &label, const Cloud::Ptr &cloud, const agex::apps::PipelineParams &params, int k,
           int repeat)
{
  // The whole pipeline, stage by stage.
  std::map<std::string, std::vector<double>> stage_ms;
  agex::apps::PipelineResult prepared;
  for (int r = 0; r < repeat; ++r)
  {
    prepared = agex::apps::runDepthPipeline (cloud, params);
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
}  // namespace

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  agex::apps::PipelineParams params;
  std::vector<std::string> vector_flags, inputs;
  std::string json_path;
  int k = 20, repeat = 30;
  bool no_portrait = false;

  po::options_description general ("agex_bench [INPUT...] [options]\n"
                                    "Times AGEX (incremental vs naive) and the depth pipeline per frame");
  general.add_options () ("help,h", "show this help")
    ("input", po::value (&inputs)->multitoken (), "frame files (default: the bundled Bonn frame)")
    ("bench-k", po::value (&k)->default_value (k), "k for the incremental vs naive comparison")
    ("repeat", po::value (&repeat)->default_value (repeat), "timed runs per measurement")
    ("no-portrait", po::bool_switch (&no_portrait), "skip the 144x176 portrait view of 640x480 frames")
    ("json", po::value (&json_path), "write the figures as JSON here");
  po::options_description all;
  all.add (general).add (agex::apps::frameOptionsDescription (frame_options))
     .add (agex::apps::pipelineOptionsDescription (params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", -1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, params);
    if (k < 1 || repeat < 1)
      throw std::runtime_error ("--bench-k and --repeat must be at least 1");
    if (inputs.empty ())
      inputs.push_back (AGEX_BUNDLED_FRAME);
    if (!json_path.empty ())
      agex::checkOutputIsNotInput (json_path, inputs);

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

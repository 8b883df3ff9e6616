// mesh_tip_survival: how many labelled tips keep a point of the depth pipeline's meshes
// within a radius, at the resolution recorded and at lower ones (doc/pipeline.md, "Metric
// settings"). A developer's measuring tool, built with the tests, not installed.
//
//   mesh_tip_survival bonn BONN_DIR [SCALE ...]        keyframes, each SCALE a view of the
//                                                      whole 640x480 frame (1, 0.5, ...)
//   mesh_tip_survival synth FRAMES SEED [WxH ...]      procedural poses, kinect sensor
//   --set KEY=VALUE (anywhere, repeatable)             a pipeline setting (model key, JSON
//                                                      value) changed for every run
//
// For each resolution and part it prints the fraction of labelled tips with a mesh point
// within 5 cm, and the same with one cleaning stage turned off at a time (which stage
// takes the tips), and with a person pixel within 5 cm (what isolation left).

#include <agex/detection/depth_pipeline.h>
#include <agex/io/bonn.h>
#include <agex/io/frame_io.h>
#include <agex/simulation/synthetic_scene.h>

#include <nlohmann/json.hpp>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
constexpr float kRadius = 0.05f;

struct Tip
{
  agex::BodyPart part;
  Eigen::Vector3f point;
};

struct Variant
{
  std::string name;
  agex::DepthPipelineParams params;
};

/** Settings changed from the defaults for every run (--set key=value, model keys). */
nlohmann::json g_overrides = nlohmann::json::object ();

std::vector<Variant>
variants ()
{
  std::vector<Variant> all;
  nlohmann::json doc = agex::DepthPipelineParams ().toJson ();
  doc.merge_patch (g_overrides);
  const agex::DepthPipelineParams defaults = agex::DepthPipelineParams::fromJson (doc, "--set");
  all.push_back ({"defaults", defaults});
  auto p = defaults;
  p.remove_mixed_pixels = false;
  all.push_back ({"no mixed", p});
  p = defaults;
  p.median_window = 0;
  all.push_back ({"no median", p});
  p = defaults;
  p.spur_iterations = 0;
  all.push_back ({"no spurs", p});
  p = defaults;
  p.min_mesh_size = 1;
  p.min_mesh_area = 0.f;
  all.push_back ({"any mesh", p});
  p.remove_mixed_pixels = false;
  p.median_window = 0;
  p.spur_iterations = 0;
  all.push_back ({"all off", p});
  return all;
}

bool
near (const Cloud &cloud, const std::vector<int> &points, const Eigen::Vector3f &tip)
{
  for (const int i : points)
    if ((cloud[static_cast<std::size_t> (i)].getVector3fMap () - tip).norm () <= kRadius)
      return true;
  return false;
}

struct Tally
{
  std::map<std::string, std::map<agex::BodyPart, std::pair<int, int>>> hits;  // variant -> part -> (hit, all)
  std::map<agex::BodyPart, std::pair<int, int>> person;
  std::map<std::string, double> ms;
  std::map<std::string, double> stage_ms_;  ///< the first variant's, per stage
  std::size_t meshes_ = 0;                   ///< the first variant's
  int frames = 0;

  void add (const Cloud::Ptr &cloud, const std::vector<Tip> &tips, const std::vector<Variant> &all)
  {
    ++frames;
    for (const auto &variant : all)
    {
      const agex::DepthPipelineResult r = agex::runDepthPipeline (cloud, variant.params);
      ms[variant.name] += r.ms.back ().second;
      if (&variant == &all.front ())
      {
        for (const auto &[stage, stage_ms] : r.ms)
          stage_ms_[stage] += stage_ms;
        meshes_ += r.meshes.size ();
      }
      const std::vector<int> surface = r.meshIndices ();
      std::vector<int> people;
      for (const auto &p : r.persons)
        people.insert (people.end (), p.indices.begin (), p.indices.end ());
      for (const auto &tip : tips)
      {
        auto &h = hits[variant.name][tip.part];
        h.first += near (*r.filtered, surface, tip.point);
        ++h.second;
        if (&variant == &all.front ())
        {
          // The persons are pixels of the frame the stages ran on (the working frame, if any).
          person[tip.part].first += near (r.frame ? *r.frame : *cloud, people, tip.point);
          ++person[tip.part].second;
        }
      }
    }
  }

  void print (const std::string &title, const std::vector<Variant> &all) const
  {
    std::printf ("%s (%d frames): fraction of tips with a mesh point within %.0f cm\n", title.c_str (), frames,
                 100.0 * kRadius);
    std::printf ("  %-12s %8s %8s %8s %10s\n", "pipeline", "head", "hand", "foot", "ms/frame");
    auto row = [&] (const std::string &name, const std::map<agex::BodyPart, std::pair<int, int>> &h, double ms) {
      std::printf ("  %-12s", name.c_str ());
      for (const auto part : {agex::BodyPart::Head, agex::BodyPart::Hand, agex::BodyPart::Foot})
      {
        const auto it = h.find (part);
        if (it == h.end () || it->second.second == 0)
          std::printf (" %8s", "-");
        else
          std::printf (" %3d/%-4d", it->second.first, it->second.second);
      }
      if (ms >= 0)
        std::printf (" %10.2f", ms / std::max (1, frames));
      std::printf ("\n");
    };
    for (const auto &variant : all)
      row (variant.name, hits.at (variant.name), ms.at (variant.name));
    row ("person px", person, -1);
    std::printf ("  %s ms per stage:", all.front ().name.c_str ());
    for (const auto &[stage, total] : stage_ms_)
      std::printf (" %s %.2f", stage.c_str (), total / std::max (1, frames));
    std::printf ("\n  %s meshes per frame: %.2f\n", all.front ().name.c_str (),
                 static_cast<double> (meshes_) / std::max (1, frames));
    for (const auto &variant : all)
    {
      const auto &h = hits.at (variant.name);
      const auto it = h.find (agex::BodyPart::Hand);
      if (it != h.end () && it->second.second > 0)
        std::printf ("  hand fraction, %-10s %.3f\n", variant.name.c_str (),
                     static_cast<double> (it->second.first) / it->second.second);
    }
  }
};

int
bonn (int argc, char **argv)
{
  if (argc < 3)
    throw std::runtime_error ("bonn needs BONN_DIR [SCALE ...]");
  const std::string root = argv[2];
  std::vector<double> scales;
  for (int a = 3; a < argc; ++a)
    scales.push_back (std::stod (argv[a]));
  if (scales.empty ())
    scales = {1.0, 0.5};
  const std::vector<agex::BonnLabel> labels = agex::readBonnLabels (root + "/labels.csv");
  std::map<std::pair<std::string, std::string>, std::vector<agex::BonnLabel>> keyframes;
  for (const auto &l : labels)
    if (l.keyframe)
      keyframes[{l.sequence, l.frame}].push_back (l);
  const auto all = variants ();
  for (const double scale : scales)
  {
    Tally tally;
    for (const auto &[key, frame_labels] : keyframes)
    {
      const agex::Frame frame = agex::loadFrame (root + "/depth/" + key.first + "/" + key.second + ".png");
      agex::FrameView view;
      view.width = static_cast<int> (frame.cloud->width);
      view.height = static_cast<int> (frame.cloud->height);
      view.scale = scale;
      Cloud::Ptr cloud (new Cloud);
      agex::applyView (*frame.cloud, view, *cloud);
      std::vector<Tip> tips;
      for (const auto &l : frame_labels)
      {
        Eigen::Vector3f p;
        // The converter's defaults (agex_convert --label-radius 6 --label-depth-band 0.05).
        if (agex::liftPixelToSurface (*frame.cloud, l.tip_px.x (), l.tip_px.y (), 6, 0.05f, p))
          tips.push_back ({l.part, p});
      }
      tally.add (cloud, tips, all);
    }
    tally.print ("Bonn keyframes at " + std::to_string (static_cast<int> (640 * scale)) + "x" +
                     std::to_string (static_cast<int> (480 * scale)),
                 all);
  }
  return 0;
}

int
synth (int argc, char **argv)
{
  if (argc < 4)
    throw std::runtime_error ("synth needs FRAMES SEED [WxH ...]");
  const int frames = std::stoi (argv[2]);
  std::vector<std::pair<int, int>> sizes;
  for (int a = 4; a < argc; ++a)
  {
    int w = 0, h = 0;
    if (std::sscanf (argv[a], "%dx%d", &w, &h) != 2)
      throw std::runtime_error (std::string ("not a size: ") + argv[a]);
    sizes.emplace_back (w, h);
  }
  if (sizes.empty ())
    sizes = {{640, 480}, {320, 240}};
  const auto all = variants ();
  for (const auto &[w, h] : sizes)
  {
    agex::SynthOptions options;
    options.procedural_poses = 200;
    options.sensor = agex::SynthSensor::Kinect;
    options.seed = static_cast<std::uint64_t> (std::stoll (argv[3]));
    options.width = w;
    options.height = h;
    const agex::SynthGenerator generator (options);
    Tally tally;
    for (int f = 0; f < frames; ++f)
    {
      const agex::SynthFrame frame = generator.render (static_cast<std::uint64_t> (f));
      Cloud::Ptr cloud (new Cloud (frame.cloud));
      std::vector<Tip> tips;
      for (const auto &l : frame.labels)
        if (l.visible && l.tip.allFinite ())
          tips.push_back ({l.part, l.tip});
      if (std::getenv ("AGEX_DEBUG") && f < 3)
        for (const auto &variant : all)
        {
          const agex::DepthPipelineResult r = agex::runDepthPipeline (cloud, variant.params);
          std::size_t finite = 0;
          for (const auto &q : *r.filtered)
            finite += std::isfinite (q.z);
          std::size_t persons = 0;
          for (const auto &q : r.persons)
            persons += q.indices.size ();
          std::printf ("frame %d %s: persons %zu px, filtered %zu, meshes %zu (%zu px), spur passes %d, mixed %d\n", f,
                       variant.name.c_str (), persons, finite, r.meshes.size (), r.meshIndices ().size (),
                       r.spur_iterations, r.mixed_pixels_removed);
        }
      tally.add (cloud, tips, all);
    }
    tally.print ("synthetic kinect frames at " + std::to_string (w) + "x" + std::to_string (h), all);
  }
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  try
  {
    // --set key=value (a pipeline model key and a JSON value) anywhere after the mode.
    std::vector<char *> rest;
    for (int a = 0; a < argc; ++a)
    {
      const std::string arg = argv[a];
      if (arg == "--set" && a + 1 < argc)
      {
        const std::string kv = argv[++a];
        const auto eq = kv.find ('=');
        if (eq == std::string::npos)
          throw std::runtime_error ("--set needs key=value, got " + kv);
        g_overrides[kv.substr (0, eq)] = nlohmann::json::parse (kv.substr (eq + 1));
      }
      else
        rest.push_back (argv[a]);
    }
    argc = static_cast<int> (rest.size ());
    argv = rest.data ();
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "bonn")
      return bonn (argc, argv);
    if (mode == "synth")
      return synth (argc, argv);
    std::cerr << "usage: mesh_tip_survival bonn BONN_DIR [SCALE ...] | synth FRAMES SEED [WxH ...]\n";
    return 2;
  }
  catch (const std::exception &e)
  {
    std::cerr << "mesh_tip_survival: " << e.what () << "\n";
    return 1;
  }
}

#include <agex/io/bonn.h>
#include <agex/io/dataset_conversion.h>
#include <agex/io/input_file.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

namespace fs = std::filesystem;

namespace agex
{
std::vector<BonnLabel>
readBonnLabels (const std::string &path)
{
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw DatasetError (path + ": " + problem);
  std::ifstream in (path);
  if (!in)
    throw DatasetError (path + ": cannot open the Bonn labels file");
  std::string line;
  const std::string header = "sequence,frame,keyframe,part,instance,tip_u,tip_v,base_u,base_v";
  std::getline (in, line);
  if (!line.empty () && line.back () == '\r')
    line.pop_back ();
  if (line != header)
    throw DatasetError (path + ":1: expected the header '" + header + "'");
  std::vector<BonnLabel> labels;
  for (int number = 2; std::getline (in, line); ++number)
  {
    if (!line.empty () && line.back () == '\r')
      line.pop_back ();
    if (line.empty ())
      continue;
    const std::string where = path + ":" + std::to_string (number) + ": ";
    std::vector<std::string> cells;
    std::stringstream row (line);
    for (std::string cell; std::getline (row, cell, ',');)
      cells.push_back (cell);
    if (cells.size () != 9)
      throw DatasetError (where + "expected 9 fields, found " + std::to_string (cells.size ()));
    BonnLabel label;
    label.sequence = cells[0];
    label.frame = cells[1];
    if (cells[2] != "0" && cells[2] != "1")
      throw DatasetError (where + "keyframe must be 0 or 1");
    label.keyframe = cells[2] == "1";
    if (!parseBodyPart (cells[3], label.part))
      throw DatasetError (where + "unknown part '" + cells[3] + "'");
    const auto r = std::from_chars (cells[4].data (), cells[4].data () + cells[4].size (), label.instance);
    if (r.ec != std::errc () || label.instance < 0)
      throw DatasetError (where + "bad instance '" + cells[4] + "'");
    float values[4];
    for (int i = 0; i < 4; ++i)
    {
      const char *end = cells[5 + i].data () + cells[5 + i].size ();
      const auto fr = std::from_chars (cells[5 + i].data (), end, values[i]);
      if (fr.ec != std::errc () || fr.ptr != end || !std::isfinite (values[i]))
        throw DatasetError (where + "bad pixel coordinate '" + cells[5 + i] + "'");
    }
    label.tip_px = Eigen::Vector2f (values[0], values[1]);
    label.base_px = Eigen::Vector2f (values[2], values[3]);
    labels.push_back (label);
  }
  return labels;
}

bool
liftPixelToSurface (const pcl::PointCloud<pcl::PointXYZ> &cloud, float u, float v, int radius, float depth_band,
                    Eigen::Vector3f &point, Eigen::Vector2i *pixel)
{
  if (!cloud.isOrganized () || !std::isfinite (u) || !std::isfinite (v))
    return false;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const int cu = static_cast<int> (std::lround (u)), cv = static_cast<int> (std::lround (v));
  const int u0 = std::max (0, cu - radius), u1 = std::min (width - 1, cu + radius);
  const int v0 = std::max (0, cv - radius), v1 = std::min (height - 1, cv + radius);
  float nearest = std::numeric_limits<float>::infinity ();
  for (int y = v0; y <= v1; ++y)
    for (int x = u0; x <= u1; ++x)
      if (std::isfinite (cloud (x, y).z))
        nearest = std::min (nearest, cloud (x, y).z);
  if (!std::isfinite (nearest))
    return false;
  float best = std::numeric_limits<float>::infinity ();
  int best_x = -1, best_y = -1;
  for (int y = v0; y <= v1; ++y)
    for (int x = u0; x <= u1; ++x)
    {
      const float z = cloud (x, y).z;
      if (!std::isfinite (z) || z > nearest + depth_band)
        continue;
      const float d2 = (x - u) * (x - u) + (y - v) * (y - v);
      if (d2 < best)
      {
        best = d2;
        best_x = x;
        best_y = y;
      }
    }
  point = cloud (best_x, best_y).getVector3fMap ();
  if (pixel)
    *pixel = Eigen::Vector2i (best_x, best_y);
  return true;
}

std::vector<std::string>
BonnConversion::inputFiles () const
{
  std::vector<std::string> files{root, (fs::path (root) / "labels.csv").string ()};
  for (const auto &frame : frames)
    files.push_back (frame.second);
  return files;
}

BonnConversion
planBonnConversion (const std::string &root, const BonnConversionParams &params)
{
  BonnConversion conversion;
  conversion.root = root;
  conversion.params = params;
  const fs::path dir (root);
  conversion.labels = readBonnLabels ((dir / "labels.csv").string ());

  std::vector<std::string> &sequences = conversion.params.sequences;
  if (sequences.empty ())
    for (const auto &entry : fs::directory_iterator (dir / "depth"))
      if (entry.is_directory ())
        sequences.push_back (entry.path ().filename ().string ());
  std::sort (sequences.begin (), sequences.end (), [] (const std::string &a, const std::string &b) {
    return a.size () != b.size () ? a.size () < b.size () : a < b;
  });
  for (const auto &sequence : sequences)
  {
    const fs::path sequence_dir = dir / "depth" / sequence;
    if (!fs::is_directory (sequence_dir))
      throw std::runtime_error (sequence_dir.string () + ": no such sequence");
    for (const auto &file : collectFrameFiles ({sequence_dir.string ()}, ".png"))
      conversion.frames.emplace_back (sequence, file);
  }

  const FrameOptions &options = params.frame_options;
  const FrameView view = bonnPortraitView ();
  DatasetInfo &info = conversion.info;
  info.name = params.portrait ? "bonn-portrait" : "bonn-full";
  info.sensor = "kinect";
  info.intrinsics = params.portrait ? view.intrinsics (options.intrinsics) : options.intrinsics;
  info.width = params.portrait ? view.outputWidth () : 640;
  info.height = params.portrait ? view.outputHeight () : 480;
  info.depth_scale = options.depth_scale > 0 ? options.depth_scale : 0.016;
  std::ostringstream provenance;
  provenance << "Bonn body-part depth frames (" << root << ", BSD licence), sequences";
  for (const auto &s : sequences)
    provenance << " " << s;
  provenance << "; 8-bit depth x " << info.depth_scale << " m; intrinsics fx=" << options.intrinsics.fx
             << " fy=" << options.intrinsics.fy << " cx=" << options.intrinsics.cx << " cy=" << options.intrinsics.cy
             << (params.portrait ? "; portrait view: crop x=140 y=20 360x440 scaled by 0.4 (nearest point)" : "")
             << "; label tips and bases lifted to 3D with the nearest foreground point within " << params.label_radius
             << " px (foreground: within " << params.depth_band << " m of the window's nearest depth)";
  info.provenance = provenance.str ();
  return conversion;
}

BonnConversionStats
writeBonnDataset (const BonnConversion &conversion, const std::string &output, bool overwrite,
                  const std::function<void (std::size_t, std::size_t)> &progress)
{
  const BonnConversionParams &params = conversion.params;
  std::map<std::pair<std::string, std::string>, std::vector<BonnLabel>> by_frame;
  for (const auto &row : conversion.labels)
    by_frame[{row.sequence, row.frame}].push_back (row);
  const FrameView view = bonnPortraitView ();
  // Pixels of the full frame in the stored one.
  const auto to_view = [&] (const Eigen::Vector2f &p) {
    if (!params.portrait)
      return p;
    const cv::Point2f q = view.toView (cv::Point2f (p.x (), p.y ()));
    return Eigen::Vector2f (q.x, q.y);
  };
  FrameOptions frame_options = params.frame_options;
  frame_options.depth_scale = conversion.info.depth_scale;

  DatasetWriter writer (output, conversion.info, overwrite);
  BonnConversionStats stats;
  for (const auto &[sequence, file] : conversion.frames)
  {
    const std::string frame_name = fs::path (file).stem ().string ();
    const Frame frame = loadFrame (file, frame_options);
    pcl::PointCloud<pcl::PointXYZ> stored;
    if (params.portrait)
      applyView (*frame.cloud, view, stored);
    else
      stored = *frame.cloud;

    std::vector<PartLabel> labels;
    for (const auto &row : by_frame[{sequence, frame_name}])
    {
      PartLabel label;
      label.part = row.part;
      label.instance = row.instance;
      label.keyframe = row.keyframe;
      // 3D from the full-resolution frame, whatever the stored view.
      const bool tip_ok = liftPixelToSurface (*frame.cloud, row.tip_px.x (), row.tip_px.y (), params.label_radius,
                                              params.depth_band, label.tip);
      const bool base_ok = liftPixelToSurface (*frame.cloud, row.base_px.x (), row.base_px.y (), params.label_radius,
                                               params.depth_band, label.base);
      if (!tip_ok)
        label.tip.setConstant (std::numeric_limits<float>::quiet_NaN ());
      if (!base_ok)
        label.base.setConstant (std::numeric_limits<float>::quiet_NaN ());
      // Without a 3D tip a label cannot be scored; it stays in the file, marked invisible.
      label.visible = tip_ok;
      tip_ok ? ++stats.lifted : ++stats.unlifted;
      label.tip_px = to_view (row.tip_px);
      label.base_px = to_view (row.base_px);
      labels.push_back (label);
    }
    writer.addFrame (sequence + "_" + frame_name, sequence, stored, labels);
    ++stats.frames;
    if (progress)
      progress (stats.frames, conversion.frames.size ());
  }
  writer.commit ();
  return stats;
}
}  // namespace agex

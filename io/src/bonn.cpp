#include <agex/io/bonn.h>
#include <agex/io/input_file.h>

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

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
}  // namespace agex

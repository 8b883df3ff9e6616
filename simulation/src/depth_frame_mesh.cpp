#include <agex/simulation/depth_frame_mesh.h>

#include <agex/simulation/synth_mesh.h>
#include <agex/simulation/synth_part.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace agex
{
namespace
{
void
checkRange (double value, double lo, double hi, const char *name)
{
  if (!(value >= lo && value <= hi))
    throw std::invalid_argument (std::string ("depth mesh: ") + name + " " + std::to_string (value) + " is outside " +
                                 std::to_string (lo) + "-" + std::to_string (hi));
}

void
checkImage (const cv::Mat &image, const pcl::PointCloud<pcl::PointXYZ> &cloud, const char *what)
{
  if (image.empty ())
    return;
  if (image.type () != CV_8UC1 || image.cols != static_cast<int> (cloud.width) ||
      image.rows != static_cast<int> (cloud.height))
    throw std::invalid_argument (std::string ("depth mesh: the ") + what + " image must be 8-bit single-channel of the " +
                                 "frame's size " + std::to_string (cloud.width) + "x" + std::to_string (cloud.height) +
                                 ", got " + std::to_string (image.cols) + "x" + std::to_string (image.rows) +
                                 (image.type () != CV_8UC1 ? " of another type" : ""));
}

/** The value most of a triangle's corners have; without a majority, the nearest corner's. */
std::uint8_t
majority (const std::array<std::uint8_t, 3> &values, const std::array<float, 3> &z)
{
  if (values[0] == values[1] || values[0] == values[2])
    return values[0];
  if (values[1] == values[2])
    return values[1];
  const int nearest = static_cast<int> (std::min_element (z.begin (), z.end ()) - z.begin ());
  return values[static_cast<std::size_t> (nearest)];
}
}  // namespace

void
DepthMeshSettings::validate () const
{
  checkRange (depth_quantum, 0.0, 0.5, "depth_quantum (metres)");
  checkRange (depth_step_growth, 0.0, 0.02, "depth_step_growth (metres per squared metre)");
  checkRange (gap_steps, 0.5, 50.0, "gap_steps");
  checkRange (gap_slope, 0.0, 50.0, "gap_slope");
}

double
DepthMeshSettings::depthStep (double z) const
{
  return std::max (depth_quantum, depth_step_growth * z * z);
}

double
DepthMeshSettings::maxGap (double z, double lateral) const
{
  return gap_steps * depthStep (z) + gap_slope * lateral;
}

SynthScene
depthFrameScene (const pcl::PointCloud<pcl::PointXYZ> &cloud, const DepthMeshSettings &settings, const cv::Mat &persons,
                 const cv::Mat &parts, DepthFrameMeshStats *stats)
{
  settings.validate ();
  checkImage (persons, cloud, "person");
  checkImage (parts, cloud, "part");
  if (stats)
    *stats = DepthFrameMeshStats ();
  SynthScene scene;
  const int w = static_cast<int> (cloud.width), h = static_cast<int> (cloud.height);
  if (w < 2 || h < 2 || cloud.points.size () != static_cast<std::size_t> (w) * h)
    return scene;

  // Each valid pixel is a vertex; its ray's slopes measure its neighbours' lateral spacing.
  const std::size_t n = cloud.points.size ();
  std::vector<Eigen::Vector2f> ray (n, Eigen::Vector2f::Zero ());
  std::vector<std::uint8_t> valid (n, 0);
  for (std::size_t i = 0; i < n; ++i)
  {
    const pcl::PointXYZ &p = cloud.points[i];
    if (std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z) && p.z > 0.0f)
    {
      valid[i] = 1;
      ray[i] = Eigen::Vector2f (p.x / p.z, p.y / p.z);
    }
  }
  auto joined = [&] (std::size_t a, std::size_t b) {
    if (!valid[a] || !valid[b])
      return false;
    const double za = cloud.points[a].z, zb = cloud.points[b].z, z = std::min (za, zb);
    return std::abs (za - zb) <= settings.maxGap (z, z * static_cast<double> ((ray[a] - ray[b]).norm ()));
  };

  const bool have_persons = !persons.empty (), have_parts = !parts.empty ();
  // Triangles by the person they show (0: none), each with its part.
  std::map<int, std::vector<Eigen::Vector3i>> triangles;
  std::map<int, std::vector<SynthPart>> triangle_parts;
  auto add = [&] (std::size_t a, std::size_t b, std::size_t c) {
    const std::array<std::size_t, 3> corner{a, b, c};
    const std::array<float, 3> z{cloud.points[a].z, cloud.points[b].z, cloud.points[c].z};
    std::uint8_t part = 0, person = 0;
    if (have_parts)
    {
      std::array<std::uint8_t, 3> values{};
      for (int k = 0; k < 3; ++k)
        values[k] = parts.data[corner[k]];
      part = majority (values, z);
    }
    if (have_persons)
    {
      std::array<std::uint8_t, 3> values{};
      for (int k = 0; k < 3; ++k)
        values[k] = persons.data[corner[k]];
      person = majority (values, z);
    }
    else if (part != 0)
      person = 1;
    triangles[person].emplace_back (static_cast<int> (a), static_cast<int> (b), static_cast<int> (c));
    triangle_parts[person].push_back (static_cast<SynthPart> (part));
  };

  for (int v = 0; v + 1 < h; ++v)
    for (int u = 0; u + 1 < w; ++u)
    {
      const std::size_t a = static_cast<std::size_t> (v) * w + u, b = a + 1, c = a + w, d = c + 1;
      if (valid[a] + valid[b] + valid[c] + valid[d] < 3)
        continue;
      const bool ab = joined (a, b), ac = joined (a, c), bd = joined (b, d), cd = joined (c, d);
      const bool ad = joined (a, d), bc = joined (b, c);
      // Diagonal a-d: (a, b, d) and (a, d, c); diagonal b-c: (a, b, c) and (b, d, c).
      const bool t1 = ab && bd && ad, t2 = ad && cd && ac, t3 = ab && bc && ac, t4 = bd && cd && bc;
      const int on_ad = t1 + t2, on_bc = t3 + t4;
      if (on_ad == 0 && on_bc == 0)
        continue;
      bool use_ad = on_ad > on_bc;
      if (on_ad == on_bc)
        use_ad = std::abs (cloud.points[a].z - cloud.points[d].z) <= std::abs (cloud.points[b].z - cloud.points[c].z);
      if (use_ad)
      {
        if (t1)
          add (a, b, d);
        if (t2)
          add (a, d, c);
      }
      else
      {
        if (t3)
          add (a, b, c);
        if (t4)
          add (b, d, c);
      }
    }

  // One mesh per person (and one for the rest), each with only the vertices it uses.
  std::vector<int> remap (n, -1);
  for (auto &[person, list] : triangles)
  {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<std::size_t> used;
    for (Eigen::Vector3i &t : list)
      for (int k = 0; k < 3; ++k)
      {
        const std::size_t i = static_cast<std::size_t> (t[k]);
        if (remap[i] < 0)
        {
          remap[i] = static_cast<int> (vertices.size ());
          const pcl::PointXYZ &p = cloud.points[i];
          vertices.emplace_back (p.x, p.y, p.z);
          used.push_back (i);
        }
        t[k] = remap[i];
      }
    if (stats)
      stats->triangles += list.size ();
    auto mesh = std::make_shared<const SynthMesh> (std::move (vertices), std::move (list));
    SynthPrimitive primitive =
        SynthPrimitive::triangleMesh (mesh, person > 0 ? SynthObject::Person : SynthObject::Wall);
    if (person > 0)
    {
      primitive.person = static_cast<std::uint8_t> (person);
      primitive.triangle_parts = std::make_shared<const std::vector<SynthPart>> (std::move (triangle_parts[person]));
    }
    scene.primitives.push_back (std::move (primitive));
    for (const std::size_t i : used)
      remap[i] = -1;
  }
  if (stats)
    for (const std::uint8_t flag : valid)
      stats->vertices += flag;
  return scene;
}
}  // namespace agex

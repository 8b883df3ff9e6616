#include <agex/detection/impl/depth_pipeline.hpp>

#include <nlohmann/json.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
using Namer = std::function<std::string (const std::string &)>;

std::string
formatNumber (double v)
{
  std::ostringstream out;
  out << v;
  return out.str ();
}

/** A number setting must be finite and lie in [lo, hi] (open ends where asked). */
void
checkRange (const Namer &name, const std::string &key, double value, double lo, double hi, bool lo_open = false,
            bool hi_open = false)
{
  const bool ok = std::isfinite (value) && (lo_open ? value > lo : value >= lo) && (hi_open ? value < hi : value <= hi);
  if (!ok)
    throw std::invalid_argument (name (key) + " is " + formatNumber (value) + ", outside " + (lo_open ? "(" : "[") +
                                 formatNumber (lo) + ", " + formatNumber (hi) + (hi_open ? ")" : "]"));
}

void
checkVector (const Namer &name, const std::string &key, const Eigen::Vector3f &v, double limit)
{
  if (!v.allFinite () || v.cwiseAbs ().maxCoeff () > limit)
    throw std::invalid_argument (name (key) + " must be three finite numbers within +-" + formatNumber (limit));
}
}  // namespace

void
DepthPipelineParams::validate (const Namer &name) const
{
  // Ranges wide enough for any sensor and scene, tight enough that no setting can make one
  // frame take minutes or gigabytes.
  checkRange (name, "median_window", median_window, -1, 31);  // -1: from median_extent
  checkRange (name, "median_extent", median_extent, 0, 0.1);
  checkRange (name, "median_max_movement", median_max_movement, 0, 1);
  if (mixed_window_radius == 0)  // -1: from mixed_window_angle
    throw std::invalid_argument (name ("mixed_window_radius") + " is 0, neither -1 (by the focal length) nor in [1, 31]");
  checkRange (name, "mixed_window_radius", mixed_window_radius, -1, 31);
  checkRange (name, "mixed_window_angle", mixed_window_angle, 0, 0.05, true);
  checkRange (name, "mixed_min_jump", mixed_min_jump, 0, 1, true);
  checkRange (name, "mixed_max_veil_angle_deg", mixed_max_veil_angle_deg, 0, 90, true, true);
  checkVector (name, "crop_min", crop_min, 1000);
  checkVector (name, "crop_max", crop_max, 1000);
  if ((crop_max - crop_min).minCoeff () <= 0.f)
    throw std::invalid_argument (name ("crop_min") + " must be below " + name ("crop_max") + " on every axis");
  checkVector (name, "up", up, 1e6);
  if (!(up.norm () > 0.f))
    throw std::invalid_argument (name ("up") + " must be a non-zero vector");
  checkRange (name, "floor_max_tilt_deg", floor_max_tilt_deg, 0, 90, false, true);
  checkRange (name, "floor_distance", floor_distance, 0, 0.5, true);
  checkRange (name, "floor_min_inliers", floor_min_inliers, 3, 1e7);
  checkRange (name, "spur_min_connected", spur_min_connected, 0, 8);
  checkRange (name, "spur_iterations", spur_iterations, -1, 64);  // -1: auto
  checkRange (name, "spur_depth", spur_depth, 0, 0.5, true);
  checkRange (name, "spur_min_width", spur_min_width, 0, 0.3);
  checkRange (name, "delta_connected", delta_connected, 0, 0.3, true);
  checkRange (name, "depth_step_growth", depth_step_growth, 0, 0.02);
  checkRange (name, "min_mesh_size", min_mesh_size, -1, 1e8);  // -1: auto
  checkRange (name, "min_mesh_area", min_mesh_area, 0, 10);
  checkRange (name, "working_spacing", working_spacing, 0, 0.05);
  checkRange (name, "k", k, 1, 200);
  checkRange (name, "min_separation", min_separation, 0, 1);
  checkRange (name, "delta_orient", delta_orient, 0, 1);
}

void
DepthPipelineParams::validate () const
{
  validate ([] (const std::string &key) { return key; });
}

nlohmann::json
DepthPipelineParams::toJson () const
{
  auto vec = [] (const Eigen::Vector3f &v) { return nlohmann::json::array ({v.x (), v.y (), v.z ()}); };
  return {{"median_window", median_window},
          {"median_extent", median_extent},
          {"median_max_movement", median_max_movement},
          {"remove_mixed_pixels", remove_mixed_pixels},
          {"mixed_window_radius", mixed_window_radius},
          {"mixed_window_angle", mixed_window_angle},
          {"mixed_min_jump", mixed_min_jump},
          {"mixed_max_veil_angle_deg", mixed_max_veil_angle_deg},
          {"isolate_people", isolate_people},
          {"hidden_people", hidden_people},
          {"use_crop_box", use_crop_box},
          {"crop_min", vec (crop_min)},
          {"crop_max", vec (crop_max)},
          {"remove_floor", remove_floor},
          {"up", vec (up)},
          {"floor_max_tilt_deg", floor_max_tilt_deg},
          {"floor_distance", floor_distance},
          {"floor_min_inliers", floor_min_inliers},
          {"spur_min_connected", spur_min_connected},
          {"spur_iterations", spur_iterations},
          {"spur_depth", spur_depth},
          {"spur_min_width", spur_min_width},
          {"delta_connected", delta_connected},
          {"depth_step_growth", depth_step_growth},
          {"min_mesh_size", min_mesh_size},
          {"min_mesh_area", min_mesh_area},
          {"working_spacing", working_spacing},
          {"k", k},
          {"min_separation", min_separation},
          {"delta_orient", delta_orient}};
}

DepthPipelineParams
DepthPipelineParams::pixelSettings (DepthPipelineParams base)
{
  base.median_window = 3;
  base.mixed_window_radius = 2;
  base.spur_min_width = 0.f;
  base.min_mesh_size = -1;
  base.min_mesh_area = 0.f;
  return base;
}

DepthPipelineParams
DepthPipelineParams::fromJson (const nlohmann::json &doc, const std::string &source)
{
  const Namer name = [&source] (const std::string &key) { return source + ": pipeline." + key; };
  if (!doc.is_object ())
    throw std::invalid_argument (source + ": pipeline settings must be an object");
  DepthPipelineParams q;
  // Numbers are read as double and range-checked before narrowing: 1e300 must not wrap.
  auto number = [&] (const char *key, double lo, double hi) {
    const auto it = doc.find (key);
    if (it == doc.end () || !it->is_number ())
      throw std::invalid_argument (name (key) + " is missing or not a number");
    const double v = it->get<double> ();
    checkRange (name, key, v, lo, hi);
    return v;
  };
  auto integer = [&] (const char *key, double lo, double hi) {
    const double v = number (key, lo, hi);
    if (v != std::floor (v))
      throw std::invalid_argument (name (key) + " must be a whole number");
    return static_cast<int> (v);
  };
  auto boolean = [&] (const char *key) {
    const auto it = doc.find (key);
    if (it == doc.end () || !it->is_boolean ())
      throw std::invalid_argument (name (key) + " is missing or not true/false");
    return it->get<bool> ();
  };
  auto vector = [&] (const char *key) {
    const auto it = doc.find (key);
    if (it == doc.end () || !it->is_array () || it->size () != 3 ||
        !std::all_of (it->begin (), it->end (), [] (const nlohmann::json &v) { return v.is_number (); }))
      throw std::invalid_argument (name (key) + " is missing or not three numbers");
    Eigen::Vector3d v ((*it)[0].get<double> (), (*it)[1].get<double> (), (*it)[2].get<double> ());
    if (!v.allFinite () || v.cwiseAbs ().maxCoeff () > 1e6)
      throw std::invalid_argument (name (key) + " must be three finite numbers within +-1e6");
    return Eigen::Vector3f (v.cast<float> ());
  };
  // Wide bounds here only keep the narrowing safe; validate () applies the real ranges.
  constexpr double kWide = 1e9;
  // The metric settings (doc/pipeline.md, "Metric settings"): a model written before them
  // keeps its pixel settings (its median_window and mixed_window_radius are pixels) and
  // neither the spur width rule nor a mesh area (0).
  const auto optional = [&] (const char *key, float before) {
    return doc.contains (key) ? static_cast<float> (number (key, -kWide, kWide)) : before;
  };
  q.median_window = integer ("median_window", -kWide, kWide);
  q.median_extent = optional ("median_extent", q.median_extent);
  q.median_max_movement = static_cast<float> (number ("median_max_movement", -kWide, kWide));
  q.remove_mixed_pixels = boolean ("remove_mixed_pixels");
  q.mixed_window_radius = integer ("mixed_window_radius", -kWide, kWide);
  q.mixed_window_angle = optional ("mixed_window_angle", q.mixed_window_angle);
  q.mixed_min_jump = static_cast<float> (number ("mixed_min_jump", -kWide, kWide));
  q.mixed_max_veil_angle_deg = static_cast<float> (number ("mixed_max_veil_angle_deg", -kWide, kWide));
  // Models of agex 0.1 know no people: their crop box isolated the person.
  q.isolate_people = doc.contains ("isolate_people") ? boolean ("isolate_people") : false;
  q.hidden_people = doc.contains ("hidden_people") ? boolean ("hidden_people") : false;
  q.use_crop_box = doc.contains ("use_crop_box") ? boolean ("use_crop_box") : true;
  q.crop_min = vector ("crop_min");
  q.crop_max = vector ("crop_max");
  q.remove_floor = boolean ("remove_floor");
  q.up = vector ("up");
  q.floor_max_tilt_deg = static_cast<float> (number ("floor_max_tilt_deg", -kWide, kWide));
  q.floor_distance = static_cast<float> (number ("floor_distance", -kWide, kWide));
  q.floor_min_inliers = integer ("floor_min_inliers", -kWide, kWide);
  q.spur_min_connected = integer ("spur_min_connected", -kWide, kWide);
  q.spur_iterations = integer ("spur_iterations", -kWide, kWide);
  q.spur_depth = static_cast<float> (number ("spur_depth", -kWide, kWide));
  q.spur_min_width = optional ("spur_min_width", 0.f);
  q.delta_connected = static_cast<float> (number ("delta_connected", -kWide, kWide));
  // Earlier models used fixed thresholds at every depth.
  q.depth_step_growth = doc.contains ("depth_step_growth") ? static_cast<float> (number ("depth_step_growth", -kWide, kWide)) : 0.f;
  q.min_mesh_size = integer ("min_mesh_size", -kWide, kWide);
  q.min_mesh_area = optional ("min_mesh_area", 0.f);
  // Models written before the working density ran at the sensor's.
  q.working_spacing = optional ("working_spacing", 0.f);
  q.k = integer ("k", -kWide, kWide);
  // Models written before it took k points on every mesh.
  q.min_separation = optional ("min_separation", 0.f);
  q.delta_orient = static_cast<float> (number ("delta_orient", -kWide, kWide));
  q.validate (name);
  return q;
}

DepthPipelineResult
runDepthPipeline (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &cloud, const DepthPipelineParams &params)
{
  DepthPipeline<pcl::PointXYZ> pipeline;
  pipeline.setParams (params);
  pipeline.setInputCloud (cloud);
  DepthPipelineResult result;
  pipeline.compute (result);
  return result;
}

Eigen::Vector2i
DepthPipelineResult::inputPixel (int working_index) const
{
  const int width = filtered ? static_cast<int> (filtered->width) : 0;
  if (width <= 0 || working_index < 0)
    return Eigen::Vector2i (-1, -1);
  return Eigen::Vector2i (stride * (working_index % width) + offset, stride * (working_index / width) + offset);
}

int
DepthPipelineResult::workingIndex (int u, int v) const
{
  if (!filtered || u < 0 || v < 0 || stride < 1)
    return -1;
  const int wu = u / stride, wv = v / stride;
  const int width = static_cast<int> (filtered->width), height = static_cast<int> (filtered->height);
  return wu < width && wv < height ? wv * width + wu : -1;
}

std::vector<pcl::PointIndices>
DepthPipelineResult::meshesInInput () const
{
  if (stride <= 1)
    return meshes;
  const int width = static_cast<int> (input_width), height = static_cast<int> (input_height);
  std::vector<pcl::PointIndices> out (meshes.size ());
  for (std::size_t m = 0; m < meshes.size (); ++m)
  {
    for (const auto i : meshes[m].indices)
    {
      const Eigen::Vector2i sampled = inputPixel (i);
      for (int v = sampled.y () - offset; v < sampled.y () - offset + stride && v < height; ++v)
        for (int u = sampled.x () - offset; u < sampled.x () - offset + stride && u < width; ++u)
          if (u >= 0 && v >= 0)
            out[m].indices.push_back (v * width + u);
    }
    std::sort (out[m].indices.begin (), out[m].indices.end ());
  }
  return out;
}

std::vector<int>
DepthPipelineResult::meshIndices () const
{
  std::vector<int> surface;
  for (const auto &mesh : meshes)
    surface.insert (surface.end (), mesh.indices.begin (), mesh.indices.end ());
  return surface;
}
}  // namespace agex

PCL_INSTANTIATE (DepthPipeline, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGB)(pcl::PointXYZRGBA))

#pragma once
// The ideal half of rendering (doc/synthetic.md, "Renderer"): rays cast through each
// pixel (and, near silhouettes, through sub-pixel samples) give the exact surfaces a
// pixel sees; a DepthSensor (depth_sensor.h) then turns those ideal hits into the depth
// a real sensor would measure. renderScene (synthetic_scene.h) runs both.

#include <agex/simulation/synthetic_scene.h>

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <vector>

namespace agex
{
/** A ray's nearest surface. */
struct RayHit
{
  double t = -1.0;  ///< along the unit ray, -1 = none
  int primitive = -1;
  int triangle = -1;  ///< of a mesh primitive
  double cos = 0.0;   ///< |normal . ray|
};

/** Casts rays into a scene fast: its bounded primitives binned by the image tiles
  * their bounding spheres cover (planes are tested everywhere). */
class RayCaster
{
public:
  static constexpr int kTile = 8;

  /** widen_right_px_m, widen_left_px_m: each primitive's bins also cover this many
    * pixel-metres (pixels at 1 m depth) to the right / left, for rays that do not start
    * at the camera (the kinect's projector rays). */
  RayCaster (const SynthScene &scene, const SensorModel &sensor, double widen_right_px_m = 0.0,
             double widen_left_px_m = 0.0);

  /** Nearest hit of the ray through pixel (u, v) (origin o, unit direction d). */
  RayHit trace (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, bool planes) const;
  /** True if some bounded primitive may cover pixel (u, v). */
  bool anyAt (int u, int v) const;
  /** True if a bounded primitive blocks the segment o + t d, t in (0, length). */
  bool occluded (int u, int v, const Eigen::Vector3d &o, const Eigen::Vector3d &d, double length) const;

private:
  struct Box
  {
    int index = 0, u0 = 0, v0 = 0, u1 = 0, v1 = 0;
    Eigen::Vector3d c;
    double r2 = 0.0;
  };
  const SynthScene &scene_;
  int w_, h_, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<int> planes_;
  std::vector<Box> boxes_;
  std::vector<std::vector<int>> bins_;
};

/** The unit ray through (sub)pixel (u, v) of a sensor. */
struct PixelRays
{
  const CameraIntrinsics &k;
  Eigen::Vector3d operator() (double u, double v) const
  {
    return Eigen::Vector3d ((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0).normalized ();
  }
};

/** The samples a pixel integrates: hits[0..count) along dirs[0..count), each standing
  * for `weight` of the ss x ss samples. */
struct PixelSamples
{
  std::vector<RayHit> hits;
  std::vector<Eigen::Vector3d> dirs;
  std::size_t count = 1;
  double weight = 1.0;
  bool uniform = true;  ///< the centre sample stands for all of them

  explicit PixelSamples (int ss) : hits (static_cast<std::size_t> (ss) * ss), dirs (hits.size ()) {}
};

/** What a pixel's samples add up to: hits per object class, the nearest depth per
  * class, the depth range, and the amplitude sums of a time-of-flight blend. */
struct PixelIntegral
{
  static constexpr double kNone = std::numeric_limits<double>::infinity ();
  int counts[5] = {0, 0, 0, 0, 0};
  double nearest[5] = {kNone, kNone, kNone, kNone, kNone};
  double zmin = kNone, zmax = -kNone;
  double amp_sum = 0.0, amp_range = 0.0;
};

/** The point at depth z on pixel (u, v)'s ray, as agex::depthImageToCloud places it. */
pcl::PointXYZ pointOnPixelRay (const CameraIntrinsics &k, int u, int v, double z);

/** No part or person label where the frame's cloud has no depth. */
void clearLabelsWithoutDepth (SynthFrame &frame);
}  // namespace agex

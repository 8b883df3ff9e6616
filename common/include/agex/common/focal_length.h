#pragma once
// The focal lengths agex accepts: one range for the frame input, the apps' flags, the Python
// module and the stages that derive sizes (cells, bins, windows) from a focal length; and
// their estimate from an organized cloud, for clouds that carry no intrinsics (PCD files).

#include <pcl/point_cloud.h>

#include <algorithm>
#include <cmath>

namespace agex
{
/** Focal lengths agex accepts, pixels. Depth cameras have about 100 to a few thousand; far
  * outside that a frame's metric sizes no longer fit its pixel grid (a 1e-6 px focal length
  * puts neighbouring pixels kilometres apart). */
constexpr double kMinFocalLength = 1e-3;
constexpr double kMaxFocalLength = 1e6;

/** Whether f pixels lies in [kMinFocalLength, kMaxFocalLength] (false for NaN). */
inline bool
saneFocalLength (double f)
{
  return f >= kMinFocalLength && f <= kMaxFocalLength;
}

/** \brief The focal lengths of the pinhole camera that made an organized cloud: u = fx x / z
  * + cx and v = fy y / z + cy fitted by least squares on a lattice of about 4,800 pixels (the
  * fit agex::PersonSegmentation makes). Only points with a finite position and z > 0 take
  * part. \return false (fx, fy unchanged) for an unorganized cloud, fewer than 16 points, or
  * points that all share one viewing ray in x or in y; the values are not range-checked
  * (saneFocalLength). */
template <typename PointT> bool
estimateFocalLengths (const pcl::PointCloud<PointT> &cloud, float &fx, float &fy)
{
  if (!cloud.isOrganized () || cloud.empty ())
    return false;
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  const int stride = std::max (1, static_cast<int> (std::lround (std::sqrt (cloud.size () / 4800.0))));
  double m = 0, su = 0, sa = 0, saa = 0, sua = 0, sv = 0, sb = 0, sbb = 0, svb = 0;
  for (int v = stride / 2; v < height; v += stride)
    for (int u = stride / 2; u < width; u += stride)
    {
      const PointT &p = cloud[static_cast<std::size_t> (v) * width + u];
      if (!std::isfinite (p.x) || !std::isfinite (p.y) || !std::isfinite (p.z) || !(p.z > 0.f))
        continue;
      const double a = p.x / p.z, b = p.y / p.z;
      m += 1, su += u, sa += a, saa += a * a, sua += u * a;
      sv += v, sb += b, sbb += b * b, svb += v * b;
    }
  if (m < 16)
    return false;
  const double var_a = saa - sa * sa / m, var_b = sbb - sb * sb / m;
  if (!(var_a > 1e-12) || !(var_b > 1e-12))
    return false;
  const double efx = (sua - su * sa / m) / var_a, efy = (svb - sv * sb / m) / var_b;
  if (!std::isfinite (efx) || !std::isfinite (efy))
    return false;
  fx = static_cast<float> (efx);
  fy = static_cast<float> (efy);
  return true;
}
}  // namespace agex

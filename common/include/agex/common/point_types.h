#pragma once
// Point types shared by every agex module, registered with PCL so that PCD I/O
// and the usual templated algorithms work on them.

#include <pcl/pcl_macros.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <Eigen/Core>
#include <cstdint>

namespace agex
{
/** \brief An AGEX interest point: a geodesic extremum of a surface mesh.
  *
  * x, y, z        position (metres, camera frame)
  * orientation    unit vector pointing from the mesh interior towards the extremity
  *                (zero for the first point of a mesh, the geodesic centroid)
  * geodesic_distance  geodesic distance (metres) from the points found before it
  *                    in the same mesh, at the time it was selected (0 for the centroid)
  * rank           1-based position in the mesh's AGEX sequence (1 = centroid)
  * mesh           index of the mesh it belongs to
  * u, v           pixel column and row in the organized input cloud
  */
struct EIGEN_ALIGN16 InterestPoint
{
  PCL_ADD_POINT4D;
  float orientation[3];
  float geodesic_distance;
  std::int32_t rank;
  std::int32_t mesh;
  std::int32_t u;
  std::int32_t v;

  InterestPoint ()
    : orientation{0.f, 0.f, 0.f}, geodesic_distance (0.f), rank (0), mesh (0), u (0), v (0)
  {
    x = y = z = 0.f;
    data[3] = 1.f;
  }

  Eigen::Map<Eigen::Vector3f> getOrientationVector3fMap () { return Eigen::Map<Eigen::Vector3f> (orientation); }
  Eigen::Map<const Eigen::Vector3f> getOrientationVector3fMap () const
  {
    return Eigen::Map<const Eigen::Vector3f> (orientation);
  }

  PCL_MAKE_ALIGNED_OPERATOR_NEW
};

/** \brief A depth patch around an interest point (agex::DepthPatchEstimation).
  *
  * patch            kMaxSize x kMaxSize cells, row-major (row = patch y, pointing down
  *                  along the orientation); a patch of size n < kMaxSize uses the
  *                  first n * n values (row-major n x n) and leaves the rest 0. Each
  *                  cell is the depth of the sampled pixel minus the interest point's
  *                  depth (metres, positive = farther away), clamped to +-clamp;
  *                  invalid or out-of-frame pixels hold the background value.
  * orientation      the 3D orientation the patch was aligned with (the patch's +y axis
  *                  follows its image projection); zero when the patch was not rotated
  *                  (patch axes = image axes)
  * size             cells per side (0: no patch computed)
  * metres_per_cell  cell pitch in metres at the interest point's depth
  */
struct DepthPatch
{
  static constexpr int kMaxSize = 41;
  static constexpr int kMaxCells = kMaxSize * kMaxSize;

  float patch[kMaxCells];
  float orientation[3];
  std::int32_t size;
  float metres_per_cell;

  DepthPatch () : patch{}, orientation{0.f, 0.f, 0.f}, size (0), metres_per_cell (0.f) {}

  /** Cell (row, col) of a size x size patch. */
  float &at (int row, int col) { return patch[row * size + col]; }
  float at (int row, int col) const { return patch[row * size + col]; }

  Eigen::Map<Eigen::Vector3f> getOrientationVector3fMap () { return Eigen::Map<Eigen::Vector3f> (orientation); }
  Eigen::Map<const Eigen::Vector3f> getOrientationVector3fMap () const
  {
    return Eigen::Map<const Eigen::Vector3f> (orientation);
  }
};
}  // namespace agex

POINT_CLOUD_REGISTER_POINT_STRUCT (agex::InterestPoint,
  (float, x, x)
  (float, y, y)
  (float, z, z)
  (float[3], orientation, orientation)
  (float, geodesic_distance, geodesic_distance)
  (std::int32_t, rank, rank)
  (std::int32_t, mesh, mesh)
  (std::int32_t, u, u)
  (std::int32_t, v, v))


static_assert (agex::DepthPatch::kMaxCells == 1681, "the registered patch field below is float[1681]");
POINT_CLOUD_REGISTER_POINT_STRUCT (agex::DepthPatch,
  (float[1681], patch, patch)
  (float[3], orientation, orientation)
  (std::int32_t, size, size)
  (float, metres_per_cell, metres_per_cell))

#pragma once
// The 8-neighbourhood of an organized cloud and the "connected" relation that
// both the surface segmenter and the AGEX geodesic graph are built on, kept in
// one place so that a mesh found by one is exactly a connected graph for the other.

#include <pcl/point_cloud.h>
#include <pcl/types.h>
#include <algorithm>
#include <cmath>

namespace agex
{
/** Pixel offsets (du, dv) of the four "forward" 8-neighbours. Visiting them from
  * every pixel visits every undirected 8-neighbour edge exactly once. */
constexpr int kForwardNeighbours[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};

/** All eight neighbour offsets (du, dv). */
constexpr int kAllNeighbours[8][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1},
                                      {-1, 0}, {1, -1}, {0, -1}, {-1, -1}};

template <typename PointT> inline bool
isFinitePoint (const PointT &p)
{
  return std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z);
}

/** Squared 3D distance between two points. */
template <typename PointT> inline float
squaredDistance3D (const PointT &a, const PointT &b)
{
  const float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return dx * dx + dy * dy + dz * dz;
}

/** \brief Whether neighbours a and b are connected: their 3D distance is below
  * max (delta, growth z^2), z the larger of their depths. A depth camera's steps grow with
  * the square of the depth (a structured-light Kinect's are about 0.0029 z^2 metres), so a
  * fixed delta that joins a surface at 2 m cuts it into pieces of single depth steps at 4 m.
  * growth 0: the fixed delta of the paper. */
template <typename PointT> inline bool
connectedNeighbours (const PointT &a, const PointT &b, float delta, float growth)
{
  const float z = std::max (a.z, b.z);
  const float limit = std::max (delta, growth * z * z);
  return squaredDistance3D (a, b) < limit * limit;
}

/** \brief Calls edge(i, j, length) for every 8-neighbour pair (i, j) of an organized
  * cloud where both points are finite and selected by mask (nullptr: all) and
  * their 3D distance is below max_edge_length.
  * \param[in] mask per-point flags (size = cloud.size()) or nullptr
  */
template <typename PointT, typename EdgeFn> void
forEachOrganizedEdge (const pcl::PointCloud<PointT> &cloud, const unsigned char *mask,
                      float max_edge_length, EdgeFn &&edge)
{
  const int width = static_cast<int> (cloud.width);
  const int height = static_cast<int> (cloud.height);
  const float max_sq = max_edge_length * max_edge_length;
  auto selected = [&] (int idx) {
    return (!mask || mask[idx] != 0) && isFinitePoint (cloud[idx]);
  };
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const int i = v * width + u;
      if (!selected (i))
        continue;
      for (const auto &d : kForwardNeighbours)
      {
        const int nu = u + d[0], nv = v + d[1];
        if (nu < 0 || nu >= width || nv >= height)
          continue;
        const int j = nv * width + nu;
        if (!selected (j))
          continue;
        const float sq = squaredDistance3D (cloud[i], cloud[j]);
        if (sq < max_sq)
          edge (i, j, std::sqrt (sq));
      }
    }
}

/** A rectangle of pixels, inclusive; empty when u_min > u_max. */
struct PixelBox
{
  int u_min = 0, u_max = -1, v_min = 0, v_max = -1;
  bool empty () const { return u_min > u_max || v_min > v_max; }
};

/** The smallest rectangle holding every pixel of indices, grown by margin pixels on each
  * side and clipped to the width x height image: what a filter with a window of that radius
  * reads around the points it filters. */
inline PixelBox
boundingPixelBox (const pcl::Indices &indices, int width, int height, int margin)
{
  PixelBox box;
  if (indices.empty () || width <= 0 || height <= 0)
    return box;
  box.u_min = width, box.v_min = height;
  for (const auto index : indices)
  {
    const int u = index % width, v = index / width;
    box.u_min = std::min (box.u_min, u), box.u_max = std::max (box.u_max, u);
    box.v_min = std::min (box.v_min, v), box.v_max = std::max (box.v_max, v);
  }
  box.u_min = std::max (0, box.u_min - margin), box.u_max = std::min (width - 1, box.u_max + margin);
  box.v_min = std::max (0, box.v_min - margin), box.v_max = std::min (height - 1, box.v_max + margin);
  return box;
}
}  // namespace agex

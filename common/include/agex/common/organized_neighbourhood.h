#pragma once
// The 8-neighbourhood of an organized cloud and the "connected" relation that
// both the surface segmenter and the AGEX geodesic graph are built on, kept in
// one place so that a mesh found by one is exactly a connected graph for the other.

#include <pcl/point_cloud.h>
#include <pcl/types.h>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

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

/** Per image row, the columns [first, last] a filter with a window of margin pixels reads
  * around the pixels of indices: from the leftmost to the rightmost column within margin of
  * one of them in the rows within margin (empty when first > last). Tighter than one
  * rectangle around all of them: people at different distances span different rows. */
inline void
rowSpans (const pcl::Indices &indices, int width, int height, int margin, std::vector<std::pair<int, int>> &spans)
{
  spans.assign (height > 0 ? static_cast<std::size_t> (height) : 0u, {width, -1});
  if (width <= 0 || height <= 0)
    return;
  std::vector<std::pair<int, int>> own (static_cast<std::size_t> (height), {width, -1});
  for (const auto index : indices)
  {
    const int v = index / width, u = index - v * width;
    auto &row = own[static_cast<std::size_t> (v)];
    row.first = std::min (row.first, u), row.second = std::max (row.second, u);
  }
  for (int v = 0; v < height; ++v)
  {
    const auto &row = own[static_cast<std::size_t> (v)];
    if (row.first > row.second)
      continue;
    for (int w = std::max (0, v - margin); w <= std::min (height - 1, v + margin); ++w)
    {
      auto &span = spans[static_cast<std::size_t> (w)];
      span.first = std::min (span.first, std::max (0, row.first - margin));
      span.second = std::max (span.second, std::min (width - 1, row.second + margin));
    }
  }
}
}  // namespace agex

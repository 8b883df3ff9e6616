// Shortcuts the filters take, against the plain computation they stand for:
// - agex::SpurFilter keeps each point's connected neighbours from the first pass and only
//   revisits the neighbours of removed points: the same points as the plain erosion (every
//   pass testing every remaining point against its 8 neighbours), written out here;
// - agex::MixedPixelFilter precomputes ranges (NaN for invalid points) and lets them skip
//   invalid neighbours: the same points as isMixedPixel, which computes everything per test.

#include "test_support.h"

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/spur_filter.h>

#include <random>

namespace
{
using namespace agex_test;

/** The erosion as SpurFilter documents it, pass by pass, on the points of indices. */
std::vector<int>
plainErosion (const Cloud &cloud, const std::vector<int> &indices, int iterations, int min_connected, float delta)
{
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  std::vector<unsigned char> kept (cloud.size (), 0);
  for (const int i : indices)
    kept[i] = isFinite (cloud[i]);
  for (int pass = 0; pass < iterations; ++pass)
  {
    std::vector<unsigned char> next = kept;
    for (int i = 0; i < static_cast<int> (cloud.size ()); ++i)
    {
      if (!kept[i])
        continue;
      int connected = 0;
      for (const auto &d : agex::kAllNeighbours)
      {
        const int u = i % width + d[0], v = i / width + d[1];
        if (u >= 0 && u < width && v >= 0 && v < height && kept[v * width + u] &&
            agex::squaredDistance3D (cloud[i], cloud[v * width + u]) < delta * delta)
          ++connected;
      }
      next[i] = connected >= min_connected;
    }
    kept.swap (next);
  }
  std::vector<int> out;
  for (const int i : indices)
    if (kept[i])
      out.push_back (i);
  return out;
}

/** A frame of random blobs: depth steps, single-pixel holes and strands, so that
  * erosion goes on for several passes. */
Cloud::Ptr
blobFrame (int width, int height, unsigned seed)
{
  std::mt19937 rng (seed);
  std::uniform_real_distribution<float> unit (0.f, 1.f);
  Cloud::Ptr cloud = nanCloud (width, height);
  for (int blob = 0; blob < 12; ++blob)
  {
    const int cu = static_cast<int> (rng () % width), cv = static_cast<int> (rng () % height);
    const int r = 1 + static_cast<int> (rng () % 7);
    const float z = 1.5f + unit (rng);
    for (int v = std::max (0, cv - r); v <= std::min (height - 1, cv + r); ++v)
      for (int u = std::max (0, cu - r); u <= std::min (width - 1, cu + r); ++u)
        if (unit (rng) < 0.93f)
          (*cloud) (u, v) = pcl::PointXYZ (0.01f * u, 0.01f * v, z + 0.01f * unit (rng));
  }
  return cloud;
}

TEST (SpurFilter, SamePointsAsThePlainErosion)
{
  int removed = 0, compared = 0;
  for (unsigned seed = 1; seed <= 8; ++seed)
  {
    const Cloud::Ptr cloud = blobFrame (40, 30, seed);
    std::vector<int> all, some;
    for (int i = 0; i < static_cast<int> (cloud->size ()); ++i)
    {
      all.push_back (i);
      if (i % 5 != 0)
        some.push_back (i);
    }
    for (const auto *indices : {&all, &some})
      for (int iterations : {1, 2, 3, 6, 16})
        for (int min_connected : {0, 3, 6, 8})
          for (float delta : {0.02f, 0.05f})
          {
            agex::SpurFilter<pcl::PointXYZ> filter;
            filter.setInputCloud (cloud);
            if (indices == &some)
              filter.setIndices (pcl::IndicesPtr (new pcl::Indices (some)));
            filter.setIterations (iterations);
            filter.setMinConnected (min_connected);
            filter.setDeltaConnected (delta);
            pcl::Indices kept;
            filter.filter (kept);
            const std::vector<int> expected = plainErosion (*cloud, *indices, iterations, min_connected, delta);
            ASSERT_EQ (std::vector<int> (kept.begin (), kept.end ()), expected)
                << "seed " << seed << " iterations " << iterations << " min connected " << min_connected
                << " delta " << delta << (indices == &some ? " (indices)" : "");
            removed += static_cast<int> (plainErosion (*cloud, *indices, 0, 0, delta).size () - expected.size ());
            ++compared;
          }
  }
  EXPECT_EQ (compared, 8 * 2 * 5 * 4 * 2);
  EXPECT_GT (removed, 5000);  // the erosions did remove points, over several passes
}
TEST (MixedPixelFilter, SamePointsAsTheTestOfEachPoint)
{
  int mixed = 0;
  for (unsigned seed = 1; seed <= 6; ++seed)
  {
    const Cloud::Ptr cloud = blobFrame (40, 30, seed);
    // Veils between blobs and the odd point with an infinite or NaN coordinate.
    std::mt19937 rng (seed);
    for (int i = 0; i < static_cast<int> (cloud->size ()); ++i)
    {
      pcl::PointXYZ &p = (*cloud)[i];
      const unsigned r = rng () % 100;
      if (r < 2)
        p.x = r == 0 ? std::numeric_limits<float>::infinity () : nanf_ ();
      else if (r < 30 && !isFinite (p))
        p = pcl::PointXYZ (0.01f * (i % 40), 0.01f * (i / 40), 1.5f + 2.f * static_cast<float> (rng () % 1000) / 1000.f);
    }
    for (float margin : {0.f, 0.1f})
    {
      agex::MixedPixelFilter<pcl::PointXYZ> filter;
      filter.setInputCloud (cloud);
      filter.setInteriorMargin (margin);
      filter.setNegative (true);
      pcl::Indices found;
      filter.filter (found);
      std::vector<int> expected;
      for (int i = 0; i < static_cast<int> (cloud->size ()); ++i)
        if (isFinite ((*cloud)[i]) && filter.isMixedPixel (i))
          expected.push_back (i);
      ASSERT_EQ (std::vector<int> (found.begin (), found.end ()), expected) << "seed " << seed;
      mixed += static_cast<int> (expected.size ());
    }
  }
  EXPECT_GT (mixed, 100);
}
}  // namespace

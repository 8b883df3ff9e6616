// agex::MixedPixelFilter and agex::SpurFilter against PCL's filter conventions,
// and agex::SurfaceSegmentation (8-connected meshes), on synthetic organized clouds.

#include "test_support.h"

#include <agex/common/organized_neighbourhood.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/spur_filter.h>
#include <agex/filters/surface_segmentation.h>

#include <pcl/console/print.h>
#include <pcl/filters/passthrough.h>
#include <pcl/segmentation/euclidean_cluster_comparator.h>
#include <pcl/segmentation/organized_connected_component_segmentation.h>

#include <algorithm>
#include <random>
#include <iterator>
#include <numeric>
#include <set>
#include <tuple>

namespace
{
using namespace agex_test;
using Mixed = agex::MixedPixelFilter<pcl::PointXYZ>;
using Spur = agex::SpurFilter<pcl::PointXYZ>;
using Segmentation = agex::SurfaceSegmentation<pcl::PointXYZ>;


std::vector<int>
sorted (std::vector<int> v)
{
  std::sort (v.begin (), v.end ());
  return v;
}

// ---------------------------------------------------------------------------
// 3. MixedPixelFilter

/** A vertical step edge seen by a 40x20 pinhole camera: a foreground plane at
  * 1.5 m (columns 0..19), `mixed` columns of pixels whose depth is linearly
  * interpolated between the two planes (what a ToF/Kinect sensor produces across a
  * silhouette), then the background plane at 3 m. Two pixels are NaN. */
struct StepEdge
{
  static constexpr int kWidth = 40, kHeight = 20, kFirstMixed = 20;
  Cloud::Ptr cloud;
  std::vector<int> mixed, nan, planes;  // index sets, increasing

  explicit StepEdge (int mixed_columns)
  {
    Camera cam;
    cam.width = kWidth;
    cam.height = kHeight;
    cam.cx = 19.5;
    cam.cy = 9.5;
    cloud = nanCloud (kWidth, kHeight);
    for (int v = 0; v < kHeight; ++v)
      for (int u = 0; u < kWidth; ++u)
      {
        const int i = v * kWidth + u;
        double z;
        if (u < kFirstMixed)
          z = 1.5;
        else if (u < kFirstMixed + mixed_columns)
          z = 1.5 + 1.5 * (u - kFirstMixed + 1) / (mixed_columns + 1);
        else
          z = 3.0;
        if ((u == 5 && v == 3) || (u == 30 && v == 12))
        {
          nan.push_back (i);
          continue;
        }
        (*cloud) (u, v) = rayPoint (cam, u, v, z);
        (u >= kFirstMixed && u < kFirstMixed + mixed_columns ? mixed : planes).push_back (i);
      }
  }
};

TEST (MixedPixelFilter, RemovesExactlyTheInterpolatedPixels)
{
  for (int columns : {1, 2})
  {
    SCOPED_TRACE (std::to_string (columns) + " mixed column(s)");
    const StepEdge edge (columns);
    Mixed filter (true);
    filter.setInputCloud (edge.cloud);
    pcl::Indices kept;
    filter.filter (kept);
    EXPECT_EQ (sorted (kept), edge.planes) << "both planes are kept, the mixed pixels go";
    std::vector<int> removed = edge.mixed;
    removed.insert (removed.end (), edge.nan.begin (), edge.nan.end ());
    EXPECT_EQ (sorted (*filter.getRemovedIndices ()), sorted (removed));
    for (const int i : edge.mixed)
      EXPECT_TRUE (filter.isMixedPixel (i)) << i;
    for (const int i : edge.planes)
      EXPECT_FALSE (filter.isMixedPixel (i)) << i;
  }
}

TEST (MixedPixelFilter, NegativeOutputsExactlyTheMixedPixels)
{
  for (int columns : {1, 2})
  {
    SCOPED_TRACE (std::to_string (columns) + " mixed column(s)");
    const StepEdge edge (columns);
    Mixed filter (true);
    filter.setInputCloud (edge.cloud);
    filter.setNegative (true);
    pcl::Indices mixed;
    filter.filter (mixed);
    EXPECT_EQ (sorted (mixed), edge.mixed);
    // NaN points are removed in negative mode too, as pcl::PassThrough does.
    std::vector<int> removed = edge.planes;
    removed.insert (removed.end (), edge.nan.begin (), edge.nan.end ());
    EXPECT_EQ (sorted (*filter.getRemovedIndices ()), sorted (removed));

    // The same points as a cloud.
    Cloud out;
    filter.filter (out);
    ASSERT_EQ (out.size (), edge.mixed.size ());
    for (std::size_t j = 0; j < out.size (); ++j)
      EXPECT_EQ (bits (out[j].z), bits ((*edge.cloud)[edge.mixed[j]].z));
  }
}

TEST (MixedPixelFilter, NanConventionMatchesPassThrough)
{
  // The PCL reference: pcl::PassThrough drops non-finite points whatever
  // negative says, and lists them among the removed indices.
  const StepEdge edge (2);
  for (bool negative : {false, true})
  {
    SCOPED_TRACE (negative ? "negative" : "positive");
    pcl::PassThrough<pcl::PointXYZ> pass (true);
    pass.setInputCloud (edge.cloud);
    pass.setFilterFieldName ("z");
    pass.setFilterLimits (negative ? 100.f : 0.f, negative ? 200.f : 100.f);  // keeps every finite point
    pass.setNegative (negative);
    pcl::Indices pass_kept;
    pass.filter (pass_kept);
    ASSERT_EQ (sorted (*pass.getRemovedIndices ()), edge.nan);

    Mixed filter (true);
    filter.setInputCloud (edge.cloud);
    filter.setNegative (negative);
    pcl::Indices kept;
    filter.filter (kept);
    const auto &removed = *filter.getRemovedIndices ();
    for (const int i : edge.nan)
    {
      EXPECT_TRUE (std::find (removed.begin (), removed.end (), i) != removed.end ()) << i;
      EXPECT_TRUE (std::find (kept.begin (), kept.end (), i) == kept.end ()) << i;
    }
    EXPECT_EQ (kept.size () + removed.size (), edge.cloud->size ());
  }
}

TEST (MixedPixelFilter, KeepOrganizedBlanksTheRemovedPoints)
{
  const StepEdge edge (2);
  for (bool negative : {false, true})
  {
    SCOPED_TRACE (negative ? "negative" : "positive");
    Mixed filter;
    filter.setInputCloud (edge.cloud);
    filter.setNegative (negative);
    filter.setKeepOrganized (true);
    Cloud out;
    filter.filter (out);
    ASSERT_EQ (out.width, edge.cloud->width);
    ASSERT_EQ (out.height, edge.cloud->height);
    EXPECT_FALSE (out.is_dense);
    const std::set<int> mixed (edge.mixed.begin (), edge.mixed.end ());
    for (int i = 0; i < static_cast<int> (out.size ()); ++i)
    {
      const bool should_keep = isFinite ((*edge.cloud)[i]) && (mixed.count (i) > 0) == negative;
      if (should_keep)
      {
        EXPECT_EQ (bits (out[i].x), bits ((*edge.cloud)[i].x)) << i;
        EXPECT_EQ (bits (out[i].y), bits ((*edge.cloud)[i].y)) << i;
        EXPECT_EQ (bits (out[i].z), bits ((*edge.cloud)[i].z)) << i;
      }
      else
      {
        EXPECT_TRUE (std::isnan (out[i].x) && std::isnan (out[i].y) && std::isnan (out[i].z)) << i;
      }
    }
  }
}

TEST (MixedPixelFilter, SetIndicesRestrictsTestAndOutput)
{
  const StepEdge edge (2);
  // Rows 0..7, plus nothing else: the NaN pixel (5, 3) is among them.
  pcl::IndicesPtr rows (new pcl::Indices);
  for (int i = 0; i < 8 * StepEdge::kWidth; ++i)
    rows->push_back (i);
  Mixed filter (true);
  filter.setInputCloud (edge.cloud);
  filter.setIndices (rows);
  pcl::Indices kept;
  filter.filter (kept);
  std::vector<int> expected_kept, expected_removed;
  for (const int i : *rows)
  {
    const bool plane = std::binary_search (edge.planes.begin (), edge.planes.end (), i);
    (plane ? expected_kept : expected_removed).push_back (i);
  }
  EXPECT_EQ (sorted (kept), expected_kept);
  EXPECT_EQ (sorted (*filter.getRemovedIndices ()), expected_removed) << "removed = complement within the indices";

  // Only the two mixed columns and one foreground pixel selected: neighbours are
  // still read from the whole cloud, so the mixed pixels are still recognised.
  pcl::IndicesPtr few (new pcl::Indices{5 * StepEdge::kWidth + 3, 5 * StepEdge::kWidth + 20,
                                        5 * StepEdge::kWidth + 21, 17 * StepEdge::kWidth + 21});
  filter.setIndices (few);
  filter.filter (kept);
  EXPECT_EQ (sorted (kept), std::vector<int> ({5 * StepEdge::kWidth + 3}));
  filter.setNegative (true);
  filter.filter (kept);
  EXPECT_EQ (sorted (kept), std::vector<int> ({5 * StepEdge::kWidth + 20, 5 * StepEdge::kWidth + 21,
                                               17 * StepEdge::kWidth + 21}));
  EXPECT_EQ (sorted (*filter.getRemovedIndices ()), std::vector<int> ({5 * StepEdge::kWidth + 3}));
}

/** A floor seen from a camera 2 m above it looking horizontally, rows 18 to 24.5
  * degrees below the horizon (a crop of a 640x480 frame's bottom 70 rows), 4.4 to
  * 6.2 m away. Neighbouring ranges differ by more than the minimum jump, and each
  * pixel's range lies between its neighbours', so only the veil angle (the surface
  * is at 18-24.5 degrees to the rays, above the 15 degree limit) keeps it. */
Cloud::Ptr
grazingFloor (double &min_grazing_deg, double &max_grazing_deg)
{
  Camera cam;
  cam.width = 64;
  cam.height = 70;
  cam.cx = 31.5;
  cam.cy = 239.5 - 410.0;
  Cloud::Ptr cloud = nanCloud (cam.width, cam.height);
  min_grazing_deg = 90.0;
  max_grazing_deg = 0.0;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
    {
      const Eigen::Vector3d ray ((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const double t = 2.0 / ray.y ();  // floor: y = 2 (y points down)
      (*cloud) (u, v) = rayPoint (cam, u, v, t);
      const double grazing = std::asin (ray.normalized ().y ()) * 180.0 / M_PI;  // ray vs floor plane
      min_grazing_deg = std::min (min_grazing_deg, grazing);
      max_grazing_deg = std::max (max_grazing_deg, grazing);
    }
  return cloud;
}

TEST (MixedPixelFilter, GrazingFloorIsNotRemoved)
{
  double min_grazing = 0.0, max_grazing = 0.0;
  const Cloud::Ptr floor = grazingFloor (min_grazing, max_grazing);
  // The fixture is meaningful: the floor is seen at a grazing angle above 15 degrees...
  ASSERT_GT (min_grazing, 17.0);
  ASSERT_LT (max_grazing, 25.0);
  // ... and its range jumps across a 2-pixel window exceed the 5 cm minimum jump.
  int large_jumps = 0, tested = 0;
  for (int v = 2; v + 2 < static_cast<int> (floor->height); ++v)
  {
    ++tested;
    const float jump = (*floor) (32, v - 2).getVector3fMap ().norm () - (*floor) (32, v + 2).getVector3fMap ().norm ();
    large_jumps += jump >= 0.05f;
  }
  ASSERT_EQ (large_jumps, tested);

  Mixed filter (true);
  filter.setInputCloud (floor);
  // isMixedPixel is public: it must use the configured veil angle before any filter() run.
  EXPECT_FALSE (filter.isMixedPixel (35 * 64 + 32)) << "isMixedPixel before filter()";
  pcl::Indices kept;
  filter.filter (kept);
  EXPECT_EQ (kept.size (), floor->size ()) << "a floor seen at 18-24 degrees is a surface, not a veil";
  EXPECT_TRUE (filter.getRemovedIndices ()->empty ());

  // Control: allow veils up to 35 degrees and the same floor is (wrongly) taken
  // for one, which shows that the angle is what saves it above.
  filter.setMaxVeilAngle (35.f);
  EXPECT_TRUE (filter.isMixedPixel (35 * 64 + 32)) << "isMixedPixel after setMaxVeilAngle(35)";
  filter.filter (kept);
  EXPECT_GT (filter.getRemovedIndices ()->size (), floor->size () * 8 / 10);
}

TEST (MixedPixelFilter, UnorganizedOrEmptyCloudGivesEmptyOutput)
{
  QuietPcl quiet;
  Cloud::Ptr flat (new Cloud);
  for (int i = 0; i < 100; ++i)
    flat->push_back (pcl::PointXYZ (0.01f * i, 0.f, i < 50 ? 1.5f : 3.f));
  ASSERT_FALSE (flat->isOrganized ());
  for (const Cloud::Ptr &cloud : {flat, Cloud::Ptr (new Cloud), nanCloud (30, 20)})
  {
    SCOPED_TRACE (std::to_string (cloud->width) + "x" + std::to_string (cloud->height));
    for (bool negative : {false, true})
    {
      Mixed filter (true);
      filter.setInputCloud (cloud);
      filter.setNegative (negative);
      pcl::Indices kept{1, 2, 3};
      filter.filter (kept);
      EXPECT_TRUE (kept.empty ());
      Cloud out;
      filter.filter (out);
      EXPECT_TRUE (out.empty ());
    }
  }
}

// ---------------------------------------------------------------------------
// 4. SurfaceSegmentation

/** An all-NaN w x h cloud to draw rectangles in. */
Cloud::Ptr
gridCloud (int width, int height)
{
  return nanCloud (width, height);
}

/** Fills pixels (u0..u0+w-1, v0..v0+h-1) with a 4 mm grid at depth z. */
void
fillRect (Cloud &cloud, int u0, int v0, int w, int h, float z = 2.f)
{
  for (int v = v0; v < v0 + h; ++v)
    for (int u = u0; u < u0 + w; ++u)
      cloud (u, v) = pcl::PointXYZ (0.004f * u, 0.004f * v, z);
}

/** The label cloud agrees with the meshes, which are disjoint and sorted. */
void
expectLabelsMatchMeshes (const pcl::PointCloud<pcl::Label> &labels, const std::vector<pcl::PointIndices> &meshes,
                         const Cloud &cloud)
{
  ASSERT_EQ (labels.width, cloud.width);
  ASSERT_EQ (labels.height, cloud.height);
  ASSERT_EQ (labels.size (), cloud.size ());
  std::vector<std::uint32_t> expected (cloud.size (), Segmentation::kUnlabelled);
  for (std::size_t m = 0; m < meshes.size (); ++m)
  {
    EXPECT_TRUE (std::is_sorted (meshes[m].indices.begin (), meshes[m].indices.end ()));
    if (m > 0)
    {
      EXPECT_GE (meshes[m - 1].indices.size (), meshes[m].indices.size ()) << "largest first";
    }
    for (const int i : meshes[m].indices)
    {
      EXPECT_EQ (expected[i], Segmentation::kUnlabelled) << "index " << i << " in two meshes";
      EXPECT_TRUE (isFinite (cloud[i]));
      expected[i] = static_cast<std::uint32_t> (m);
    }
  }
  for (std::size_t i = 0; i < cloud.size (); ++i)
    EXPECT_EQ (labels[i].label, expected[i]) << "point " << i;
}

std::vector<std::size_t>
sizes (const std::vector<pcl::PointIndices> &meshes)
{
  std::vector<std::size_t> s;
  for (const auto &m : meshes)
    s.push_back (m.indices.size ());
  return s;
}

TEST (SurfaceSegmentation, DiagonalNeighboursAreConnected)
{
  Cloud::Ptr cloud = gridCloud (12, 12);
  fillRect (*cloud, 1, 1, 4, 4);  // (1..4, 1..4)
  fillRect (*cloud, 5, 5, 4, 4);  // (5..8, 5..8): touches the first only at (4,4)-(5,5)
  Segmentation seg;
  seg.setInputCloud (cloud);
  pcl::PointCloud<pcl::Label> labels;
  std::vector<pcl::PointIndices> meshes;
  seg.segment (labels, meshes);
  ASSERT_EQ (meshes.size (), 1u) << "8-connected: one mesh";
  EXPECT_EQ (meshes[0].indices.size (), 32u);
  expectLabelsMatchMeshes (labels, meshes, *cloud);

  // PCL's organized connected components are 4-connected and split the two squares.
  pcl::EuclideanClusterComparator<pcl::PointXYZ, pcl::Label>::Ptr comparator (
      new pcl::EuclideanClusterComparator<pcl::PointXYZ, pcl::Label>);
  comparator->setInputCloud (cloud);
  comparator->setDistanceThreshold (0.05f, false);
  pcl::OrganizedConnectedComponentSegmentation<pcl::PointXYZ, pcl::Label> pcl_seg (comparator);
  pcl_seg.setInputCloud (cloud);
  pcl::PointCloud<pcl::Label> pcl_labels;
  std::vector<pcl::PointIndices> pcl_components;
  pcl_seg.segment (pcl_labels, pcl_components);
  const std::uint32_t a = pcl_labels (1, 1).label, b = pcl_labels (5, 5).label;
  EXPECT_EQ (pcl_labels (4, 4).label, a);
  EXPECT_EQ (pcl_labels (8, 8).label, b);
  EXPECT_NE (a, b) << "PCL's 4-connected segmentation joins diagonal neighbours?";

  // Control: one more pixel apart, the squares are two meshes.
  cloud = gridCloud (12, 12);
  fillRect (*cloud, 1, 1, 4, 4);
  fillRect (*cloud, 6, 5, 4, 4);
  seg.setInputCloud (cloud);
  seg.segment (labels, meshes);
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({16, 16}));
  expectLabelsMatchMeshes (labels, meshes, *cloud);
}

TEST (SurfaceSegmentation, DeltaConnectedSplitsAtADepthJump)
{
  Cloud::Ptr cloud = gridCloud (20, 10);
  fillRect (*cloud, 0, 0, 10, 10, 2.0f);
  fillRect (*cloud, 10, 0, 10, 10, 2.1f);  // a 10 cm step
  Segmentation seg;
  seg.setInputCloud (cloud);
  pcl::PointCloud<pcl::Label> labels;
  std::vector<pcl::PointIndices> meshes;
  seg.segment (labels, meshes);  // default delta_connected 0.05
  ASSERT_EQ (sizes (meshes), std::vector<std::size_t> ({100, 100}));
  EXPECT_EQ (meshes[0].indices.front (), 0) << "equal sizes: the one with the lowest first index first";
  EXPECT_EQ (labels (9, 5).label, 0u);
  EXPECT_EQ (labels (10, 5).label, 1u);
  expectLabelsMatchMeshes (labels, meshes, *cloud);

  seg.setDeltaConnected (0.12f);  // the step (10.0 cm, 10.1 cm diagonally) is now an edge
  seg.segment (labels, meshes);
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({200}));
  expectLabelsMatchMeshes (labels, meshes, *cloud);
}

TEST (SurfaceSegmentation, MeshSizeLimitsAndOrder)
{
  // Blobs in scan order: 4, 1, 30, 12 points (so sorting is not scan order).
  Cloud::Ptr cloud = gridCloud (30, 20);
  fillRect (*cloud, 0, 0, 2, 2);     // 4
  fillRect (*cloud, 5, 0, 1, 1);     // 1
  fillRect (*cloud, 10, 3, 5, 6);    // 30
  fillRect (*cloud, 20, 10, 3, 4);   // 12
  Segmentation seg;
  seg.setInputCloud (cloud);
  pcl::PointCloud<pcl::Label> labels;
  std::vector<pcl::PointIndices> meshes;

  seg.segment (labels, meshes);
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({30, 12, 4, 1}));
  expectLabelsMatchMeshes (labels, meshes, *cloud);

  seg.setMinMeshSize (4);
  seg.segment (labels, meshes);
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({30, 12, 4}));
  expectLabelsMatchMeshes (labels, meshes, *cloud);
  EXPECT_EQ (labels (5, 0).label, Segmentation::kUnlabelled) << "a dropped mesh is unlabelled";

  seg.setMaxMeshSize (12);
  seg.segment (labels, meshes);
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({12, 4}));
  expectLabelsMatchMeshes (labels, meshes, *cloud);

  seg.setMinMeshSize (1);
  seg.segment (meshes);  // the overload without labels gives the same meshes
  EXPECT_EQ (sizes (meshes), std::vector<std::size_t> ({12, 4, 1}));

  QuietPcl quiet;
  seg.setMinMeshSize (20);  // min > max: invalid
  seg.segment (labels, meshes);
  EXPECT_TRUE (meshes.empty ());
}

TEST (SurfaceSegmentation, IndicesRestrictTheMeshes)
{
  Cloud::Ptr cloud = gridCloud (10, 10);
  fillRect (*cloud, 0, 0, 10, 10);
  // Only columns 0..2 and 6..9: two meshes, the middle columns take no part.
  pcl::IndicesPtr indices (new pcl::Indices);
  for (int v = 0; v < 10; ++v)
    for (int u : {0, 1, 2, 6, 7, 8, 9})
      indices->push_back (v * 10 + u);
  Segmentation seg;
  seg.setInputCloud (cloud);
  seg.setIndices (indices);
  pcl::PointCloud<pcl::Label> labels;
  std::vector<pcl::PointIndices> meshes;
  seg.segment (labels, meshes);
  ASSERT_EQ (sizes (meshes), std::vector<std::size_t> ({40, 30}));
  EXPECT_EQ (meshes[0].indices.front (), 6);
  expectLabelsMatchMeshes (labels, meshes, *cloud);
}

TEST (SurfaceSegmentation, UnorganizedEmptyOrAllNanInputGivesNoMeshes)
{
  QuietPcl quiet;
  Cloud::Ptr flat (new Cloud);
  for (int i = 0; i < 100; ++i)
    flat->push_back (pcl::PointXYZ (0.004f * i, 0.f, 2.f));
  for (const Cloud::Ptr &cloud : {flat, Cloud::Ptr (new Cloud), nanCloud (30, 20)})
  {
    SCOPED_TRACE (std::to_string (cloud->width) + "x" + std::to_string (cloud->height));
    Segmentation seg;
    seg.setInputCloud (cloud);
    pcl::PointCloud<pcl::Label> labels;
    std::vector<pcl::PointIndices> meshes (3);
    seg.segment (labels, meshes);
    EXPECT_TRUE (meshes.empty ());
    if (cloud->isOrganized ())
    {
      ASSERT_EQ (labels.size (), cloud->size ());
      for (const auto &l : labels)
        EXPECT_EQ (l.label, Segmentation::kUnlabelled);
    }
    else
    {
      EXPECT_TRUE (labels.empty ());
    }
  }
}

// ---------------------------------------------------------------------------
// 5. SpurFilter

/** Chebyshev distance (pixels) from pixel i to the nearest non-finite pixel or the
  * outside of the image: a pixel d > n away from both has all 8 neighbours for n
  * erosion passes on a flat grid, so it survives them. */
int
distanceToMissing (const Cloud &cloud, int i)
{
  const int w = static_cast<int> (cloud.width), h = static_cast<int> (cloud.height);
  const int u = i % w, v = i / w;
  int d = std::min ({u + 1, v + 1, w - u, h - v});
  for (int j = 0; j < static_cast<int> (cloud.size ()); ++j)
    if (!isFinite (cloud[j]))
      d = std::min (d, std::max (std::abs (j % w - u), std::abs (j / w - v)));
  return d;
}

/** Indices of the pixels of the rectangle (u0..u0+w-1, v0..v0+h-1) of a cloud width wide, increasing. */
std::vector<int>
rectIndices (int width, int u0, int v0, int w, int h)
{
  std::vector<int> indices;
  for (int v = v0; v < v0 + h; ++v)
    for (int u = u0; u < u0 + w; ++u)
      indices.push_back (v * width + u);
  return indices;
}

std::vector<int>
finiteIndices (const Cloud &cloud, bool finite = true)
{
  std::vector<int> indices;
  for (int i = 0; i < static_cast<int> (cloud.size ()); ++i)
    if (isFinite (cloud[i]) == finite)
      indices.push_back (i);
  return indices;
}

std::vector<int>
spurKept (const Cloud::Ptr &cloud, int iterations, int min_connected = 6, float delta = 0.05f)
{
  Spur filter;
  filter.setInputCloud (cloud);
  filter.setIterations (iterations);
  filter.setMinConnected (min_connected);
  filter.setDeltaConnected (delta);
  pcl::Indices kept;
  filter.filter (kept);
  return sorted (kept);
}

/** A 16x16 square (columns and rows 6..21) in a 32x32 NaN frame, with teeth of
  * lengths 1..6 on its right edge (rows 7, 9, ..., 17: one-pixel strands). */
struct Comb
{
  static constexpr int kSize = 32, kFirst = 6, kSide = 16;
  Cloud::Ptr cloud = gridCloud (kSize, kSize);
  std::vector<int> square;
  std::vector<std::pair<int, int>> teeth;  // row, length
  Comb ()
  {
    fillRect (*cloud, kFirst, kFirst, kSide, kSide);
    square = rectIndices (kSize, kFirst, kFirst, kSide, kSide);
    for (int t = 0; t < 6; ++t)
    {
      teeth.emplace_back (7 + 2 * t, t + 1);
      fillRect (*cloud, kFirst + kSide, 7 + 2 * t, t + 1, 1);
    }
  }
};

TEST (SpurFilter, OnePixelStrandGoesInteriorStays)
{
  // A 16x16 square (6..21) with three one-pixel strands: 8 pixels out of its right
  // edge, 6 up from its top edge to the image border, 4 diagonally off a corner.
  Cloud::Ptr cloud = gridCloud (32, 32);
  fillRect (*cloud, 6, 6, 16, 16);
  std::vector<int> strands;
  for (int u = 22; u < 30; ++u)
    strands.push_back (13 * 32 + u);
  for (int v = 0; v < 6; ++v)
    strands.push_back (v * 32 + 10);
  for (int k = 1; k <= 4; ++k)
    strands.push_back ((21 + k) * 32 + 21 + k);
  for (const int i : strands)
    (*cloud)[i] = pcl::PointXYZ (0.004f * (i % 32), 0.004f * (i / 32), 2.f);

  Spur filter (true);
  EXPECT_EQ (filter.getIterations (), 3);
  EXPECT_EQ (filter.getMinConnected (), 6);
  EXPECT_FLOAT_EQ (filter.getDeltaConnected (), 0.05f);
  filter.setInputCloud (cloud);
  pcl::Indices kept;
  filter.filter (kept);
  kept = sorted (kept);
  const auto &removed = *filter.getRemovedIndices ();
  for (const int i : strands)
  {
    EXPECT_TRUE (std::find (removed.begin (), removed.end (), i) != removed.end ()) << "strand pixel " << i;
    EXPECT_FALSE (std::binary_search (kept.begin (), kept.end (), i)) << "strand pixel " << i;
  }
  // The interior (3+ pixels inside the square) stays, whatever the strands.
  for (const int i : rectIndices (32, 9, 9, 10, 10))
    EXPECT_TRUE (std::binary_search (kept.begin (), kept.end (), i)) << "interior pixel " << i;
  // And nothing deeper than 3 pixels from the silhouette goes.
  for (const int i : removed)
    if (isFinite ((*cloud)[i]))
    {
      EXPECT_LE (distanceToMissing (*cloud, i), 3) << "removed pixel " << i;
    }

  // Without the strands the square erodes to exactly the 10x10 interior.
  Cloud::Ptr square = gridCloud (32, 32);
  fillRect (*square, 6, 6, 16, 16);
  EXPECT_EQ (spurKept (square, 3), rectIndices (32, 9, 9, 10, 10));
}

TEST (SpurFilter, IterationsBoundHowFarTheErosionGoes)
{
  // A square loses one ring per pass (its edge pixels have 5 connected
  // neighbours, fewer than 6), down to nothing.
  Cloud::Ptr square = gridCloud (32, 32);
  fillRect (*square, 6, 6, 16, 16);
  for (int n = 0; n <= 8; ++n)
    EXPECT_EQ (spurKept (square, n), rectIndices (32, 6 + n, 6 + n, 16 - 2 * n, 16 - 2 * n)) << n << " passes";
  EXPECT_TRUE (spurKept (square, 50).empty ());

  // A ragged edge: with min_connected 2, a tooth loses its tip pixel per pass and
  // the square (edge pixels: 5 neighbours, corners 3) stays whole; the pixel that
  // joins a tooth to the square has 3 square neighbours and always stays.
  const Comb comb;
  for (int n = 0; n <= 7; ++n)
  {
    SCOPED_TRACE (std::to_string (n) + " passes, min_connected 2");
    std::vector<int> expected = comb.square;
    for (const auto &[row, length] : comb.teeth)
      for (int k = 0; k < std::max (length - n, 1); ++k)
        expected.push_back (row * Comb::kSize + Comb::kFirst + Comb::kSide + k);
    EXPECT_EQ (spurKept (comb.cloud, n, 2), sorted (expected));
  }

  // With the defaults the erosion reaches exactly n pixels deep: everything
  // deeper stays, and some pixel n deep goes.
  std::vector<int> depth (comb.cloud->size (), 0);
  for (int i = 0; i < static_cast<int> (comb.cloud->size ()); ++i)
    if (isFinite ((*comb.cloud)[i]))
      depth[i] = distanceToMissing (*comb.cloud, i);
  for (int n = 1; n <= 5; ++n)
  {
    SCOPED_TRACE (std::to_string (n) + " passes, defaults");
    const std::vector<int> kept = spurKept (comb.cloud, n);
    int deepest_removed = 0;
    for (const int i : finiteIndices (*comb.cloud))
    {
      const bool is_kept = std::binary_search (kept.begin (), kept.end (), i);
      if (depth[i] > n)
      {
        EXPECT_TRUE (is_kept) << "pixel " << i << " is " << depth[i] << " deep";
      }
      if (!is_kept)
        deepest_removed = std::max (deepest_removed, depth[i]);
    }
    EXPECT_EQ (deepest_removed, n);
  }
}

TEST (SpurFilter, DepthJumpsAreNotConnections)
{
  // A 20x10 plane with a 10 cm step in the middle: across it neighbours are not
  // connected, so the columns on both sides of the step erode like an edge.
  Cloud::Ptr cloud = gridCloud (24, 14);
  fillRect (*cloud, 2, 2, 10, 10, 2.0f);
  fillRect (*cloud, 12, 2, 10, 10, 2.1f);
  std::vector<int> expected = rectIndices (24, 3, 3, 8, 8), right = rectIndices (24, 13, 3, 8, 8);
  expected.insert (expected.end (), right.begin (), right.end ());
  EXPECT_EQ (spurKept (cloud, 1, 6, 0.05f), sorted (expected));
  // With delta_connected above the step it is one surface: only the outer ring goes.
  EXPECT_EQ (spurKept (cloud, 1, 6, 0.15f), rectIndices (24, 3, 3, 18, 8));
}

TEST (SpurFilter, NegativeAndRemovedIndicesFollowPassThrough)
{
  Comb comb;
  (*comb.cloud) (12, 12) = nanPoint ();  // two holes in the square
  (*comb.cloud) (17, 15) = nanPoint ();
  const std::vector<int> finite = finiteIndices (*comb.cloud), nan = finiteIndices (*comb.cloud, false);
  std::vector<int> kept[2], removed[2];
  for (bool negative : {false, true})
  {
    Spur filter (true);
    filter.setInputCloud (comb.cloud);
    filter.setNegative (negative);
    pcl::Indices out;
    filter.filter (out);
    kept[negative] = sorted (out);
    removed[negative] = sorted (*filter.getRemovedIndices ());
    EXPECT_EQ (kept[negative].size () + removed[negative].size (), comb.cloud->size ());

    // The same points as a cloud.
    Cloud points;
    filter.filter (points);
    ASSERT_EQ (points.size (), out.size ());
    for (std::size_t j = 0; j < points.size (); ++j)
      EXPECT_EQ (bits (points[j].z), bits ((*comb.cloud)[out[j]].z));
  }
  ASSERT_FALSE (kept[0].empty ());
  ASSERT_FALSE (kept[1].empty ());
  // Negative gives exactly the finite points the positive run removes ...
  std::vector<int> all_kept;
  std::merge (kept[0].begin (), kept[0].end (), kept[1].begin (), kept[1].end (), std::back_inserter (all_kept));
  EXPECT_EQ (all_kept, finite) << "kept and negative-kept partition the finite points";
  // ... and NaN points are removed in both modes, as pcl::PassThrough does.
  std::vector<int> expected_removed[2];
  for (bool negative : {false, true})
  {
    std::merge (kept[!negative].begin (), kept[!negative].end (), nan.begin (), nan.end (),
                std::back_inserter (expected_removed[negative]));
    EXPECT_EQ (removed[negative], expected_removed[negative]) << (negative ? "negative" : "positive");
  }
}

TEST (SpurFilter, KeepOrganizedBlanksTheRemovedPoints)
{
  const Comb comb;
  const std::vector<int> positive = spurKept (comb.cloud, 3);
  for (bool negative : {false, true})
  {
    SCOPED_TRACE (negative ? "negative" : "positive");
    Spur filter (true);
    filter.setInputCloud (comb.cloud);
    filter.setNegative (negative);
    filter.setKeepOrganized (true);
    Cloud out;
    filter.filter (out);
    ASSERT_EQ (out.width, comb.cloud->width);
    ASSERT_EQ (out.height, comb.cloud->height);
    EXPECT_FALSE (out.is_dense);
    for (int i = 0; i < static_cast<int> (out.size ()); ++i)
    {
      const bool in_positive = std::binary_search (positive.begin (), positive.end (), i);
      if (isFinite ((*comb.cloud)[i]) && in_positive != negative)
      {
        EXPECT_EQ (bits (out[i].x), bits ((*comb.cloud)[i].x)) << i;
        EXPECT_EQ (bits (out[i].z), bits ((*comb.cloud)[i].z)) << i;
      }
      else
      {
        EXPECT_TRUE (std::isnan (out[i].x) && std::isnan (out[i].y) && std::isnan (out[i].z)) << i;
      }
    }
  }
}

TEST (SpurFilter, SetIndicesOnlyThosePointsTakePart)
{
  // A full 20x20 plane; only columns 0..9 selected. Points outside the indices do
  // not count as neighbours, so column 9 is an edge.
  Cloud::Ptr cloud = gridCloud (20, 20);
  fillRect (*cloud, 0, 0, 20, 20);
  pcl::IndicesPtr left (new pcl::Indices (rectIndices (20, 0, 0, 10, 20)));
  Spur filter (true);
  filter.setInputCloud (cloud);
  filter.setIterations (1);
  filter.setIndices (left);
  pcl::Indices kept;
  filter.filter (kept);
  const std::vector<int> expected = rectIndices (20, 1, 1, 8, 18);
  EXPECT_EQ (sorted (kept), expected);
  std::vector<int> expected_removed;
  std::set_difference (left->begin (), left->end (), expected.begin (), expected.end (),
                       std::back_inserter (expected_removed));
  EXPECT_EQ (sorted (*filter.getRemovedIndices ()), expected_removed) << "removed = complement within the indices";

  // Control: the whole frame erodes only at the image border.
  EXPECT_EQ (spurKept (cloud, 1), rectIndices (20, 1, 1, 18, 18));
}

TEST (SpurFilter, UnorganizedEmptyAllNanOrBadParametersGiveEmptyOutput)
{
  QuietPcl quiet;
  Cloud::Ptr flat (new Cloud);
  for (int i = 0; i < 100; ++i)
    flat->push_back (pcl::PointXYZ (0.004f * (i % 10), 0.004f * (i / 10), 2.f));
  ASSERT_FALSE (flat->isOrganized ());
  for (const Cloud::Ptr &cloud : {flat, Cloud::Ptr (new Cloud), nanCloud (30, 20)})
  {
    SCOPED_TRACE (std::to_string (cloud->width) + "x" + std::to_string (cloud->height));
    for (bool negative : {false, true})
    {
      Spur filter (true);
      filter.setInputCloud (cloud);
      filter.setNegative (negative);
      pcl::Indices kept{1, 2, 3};
      filter.filter (kept);
      EXPECT_TRUE (kept.empty ());
      Cloud out;
      filter.filter (out);
      EXPECT_TRUE (out.empty ());
    }
  }
  // Parameters out of range: an error and no output, not a guess.
  const Comb comb;
  for (const auto &[min_connected, iterations, delta] :
       std::vector<std::tuple<int, int, float>>{{9, 3, 0.05f}, {-1, 3, 0.05f}, {6, -1, 0.05f}, {6, 3, 0.f}, {6, 3, nanf_ ()}})
  {
    SCOPED_TRACE ("min_connected " + std::to_string (min_connected) + ", iterations " + std::to_string (iterations) +
                  ", delta " + std::to_string (delta));
    EXPECT_TRUE (spurKept (comb.cloud, iterations, min_connected, delta).empty ());
  }
  EXPECT_FALSE (spurKept (comb.cloud, 3, 6, 0.05f).empty ()) << "control";
}
}  // namespace

namespace
{
// ---------------------------------------------------------------------------
// 5b. SpurFilter in metres: the same metric scene at two resolutions of one camera

/** A body seen at depth z by a camera of focal length f (pixels) and an image of the
  * camera's field of view at that resolution (640x480 at f = 525, 320x240 at 262.5): a
  * 0.4 m x 0.5 m block with a 6 cm wide, 30 cm long limb going right from its middle, a
  * one-pixel and a two-pixel wide strand going up 15 cm from its top, and single-pixel spurs
  * on its bottom edge every 10 pixels. */
struct MetricBody
{
  Camera cam;
  double z;
  Cloud::Ptr cloud;
  std::vector<int> strands, spurs;
  // Metric layout (x right, y down, metres at depth z).
  static constexpr double kLeft = -0.3, kRight = 0.1, kTop = -0.25, kBottom = 0.25;
  static constexpr double kLimbHalf = 0.03, kLimbEnd = 0.4;

  MetricBody (double f, double depth) : z (depth)
  {
    cam.fx = cam.fy = f;
    cam.width = static_cast<int> (std::lround (640 * f / 525.0));
    cam.height = static_cast<int> (std::lround (480 * f / 525.0));
    cam.cx = (cam.width - 1) / 2.0;
    cam.cy = (cam.height - 1) / 2.0;
    cloud = nanCloud (cam.width, cam.height);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u)
      {
        const double x = metricX (u), y = metricY (v);
        const bool block = x >= kLeft && x <= kRight && y >= kTop && y <= kBottom;
        const bool limb = x > kRight && x <= kLimbEnd && std::abs (y) <= kLimbHalf;
        if (block || limb)
          (*cloud) (u, v) = rayPoint (cam, u, v, z);
      }
    // The block's first row, and the first row below it.
    const int top = rowOf (kTop), below = static_cast<int> (std::floor (kBottom * f / z + cam.cy)) + 1;
    const int strand_length = static_cast<int> (std::lround (0.15 * f / z));
    for (const auto &[first, width] : std::vector<std::pair<int, int>>{{columnOf (-0.2), 1}, {columnOf (-0.05), 2}})
      for (int v = top - strand_length; v < top; ++v)
        for (int u = first; u < first + width; ++u)
          add (u, v, strands);
    for (int u = columnOf (kLeft) + 10; u < columnOf (kRight) - 5; u += 10)
      add (u, below, spurs);
  }
  double metricX (int u) const { return (u - cam.cx) / cam.fx * z; }
  double metricY (int v) const { return (v - cam.cy) / cam.fy * z; }
  /** The first column / row at or past a metric x / y. */
  int columnOf (double x) const { return static_cast<int> (std::ceil (x * cam.fx / z + cam.cx)); }
  int rowOf (double y) const { return static_cast<int> (std::ceil (y * cam.fy / z + cam.cy)); }
  void add (int u, int v, std::vector<int> &set)
  {
    ASSERT_TRUE (u >= 0 && v >= 0 && u < cam.width && v < cam.height);
    (*cloud) (u, v) = rayPoint (cam, u, v, z);
    set.push_back (v * cam.width + u);
  }
};

std::vector<int>
metricSpurKept (const MetricBody &body, float min_width, float erosion_depth = 0.035f)
{
  Spur filter;
  filter.setInputCloud (body.cloud);
  filter.setDeltaConnected (0.03f);
  filter.setFocalLength (static_cast<float> (body.cam.fx));
  filter.setErosionDepth (erosion_depth);
  filter.setMinWidth (min_width);
  pcl::Indices kept;
  filter.filter (kept);
  return sorted (kept);
}

TEST (SpurFilter, InMetresStrandsGoAndAThinLimbStaysAtBothResolutions)
{
  for (const double f : {525.0, 262.5})
  {
    const MetricBody body (f, 2.5);
    const double pixel = body.z / f;  // metres a pixel spans at the body's depth
    SCOPED_TRACE ("f = " + std::to_string (f) + " px, " + std::to_string (body.cam.width) + "x" +
                  std::to_string (body.cam.height) + ", a pixel is " + std::to_string (pixel * 1000) + " mm");
    const std::vector<int> kept = metricSpurKept (body, 0.03f);
    const auto is_kept = [&kept] (int i) { return std::binary_search (kept.begin (), kept.end (), i); };
    // One- and two-pixel strands and one-pixel spurs go, whatever a pixel spans.
    for (const int i : body.strands)
      EXPECT_FALSE (is_kept (i)) << "strand pixel (" << i % body.cam.width << ", " << i / body.cam.width << ")";
    for (const int i : body.spurs)
      EXPECT_FALSE (is_kept (i)) << "spur pixel (" << i % body.cam.width << ", " << i / body.cam.width << ")";
    // The limb stays along its length, its middle at least 2.5 cm wide (the 3 cm minimum
    // width, less a pixel's rounding) and narrower than it was (eroded towards it). Its base
    // goes with the block's edge: within the erosion depth of the block's edge the limb's
    // points lie on the block's layers, and the block is wide (at either resolution the
    // first 3.5-4 cm; the limb is then a mesh of its own).
    int limb_columns = 0, kept_columns = 0;
    for (int u = body.columnOf (MetricBody::kRight + 0.045); body.metricX (u) <= MetricBody::kLimbEnd - 0.03; ++u)
    {
      ++limb_columns;
      int width = 0, whole = 0;
      for (int v = 0; v < body.cam.height; ++v)
      {
        const int i = v * body.cam.width + u;
        whole += isFinite ((*body.cloud)[i]);
        width += is_kept (i);
      }
      kept_columns += width > 0;
      if (std::abs (body.metricX (u) - 0.25) < pixel)
      {
        EXPECT_GE (width * pixel, 0.025) << "kept width in the limb's middle";
        EXPECT_LT (width, whole) << "the limb's sides are eroded";
      }
    }
    EXPECT_GT (limb_columns, 0);
    EXPECT_EQ (kept_columns, limb_columns) << "columns of the limb with a point kept";
    // The block's edge loses the erosion depth (3.5 cm) and no more: along its middle row,
    // the first kept pixel from the left lies 3.5 cm (rounded to pixels) inside.
    const int row = body.rowOf (0.15);
    int first = -1;
    for (int u = 0; u < body.cam.width && first < 0; ++u)
      if (is_kept (row * body.cam.width + u))
        first = u;
    ASSERT_GE (first, 0);
    EXPECT_NEAR ((first - body.columnOf (MetricBody::kLeft)) * pixel, 0.035, pixel);

    // Control: the plain erosion of the same depth takes the limb whole (it is narrower
    // than twice 3.5 cm), at both resolutions.
    const std::vector<int> plain = metricSpurKept (body, 0.f);
    for (int u = body.columnOf (MetricBody::kRight + 0.05); body.metricX (u) <= MetricBody::kLimbEnd; ++u)
      for (int v = 0; v < body.cam.height; ++v)
        EXPECT_FALSE (std::binary_search (plain.begin (), plain.end (), v * body.cam.width + u))
            << "plain erosion kept limb pixel (" << u << ", " << v << ")";
  }
}

TEST (SpurFilter, InMetresWithoutAMinWidthEachDepthGetsItsPasses)
{
  // Two 30x30 squares 0.2 m apart in depth (no connection between them): at f = 500 and
  // 0.02 m of erosion, the near one (2 m) is eroded round (0.02 * 500 / 2) = 5 passes, the
  // far one (5 m) 2 passes, exactly as the pixel erosion with those passes does.
  Camera cam;
  cam.width = 80;
  cam.height = 40;
  cam.fx = cam.fy = 500.0;
  cam.cx = 39.5;
  cam.cy = 19.5;
  const auto square = [&cam] (int u0, double z) {
    Cloud::Ptr cloud = nanCloud (cam.width, cam.height);
    for (int v = 5; v < 35; ++v)
      for (int u = u0; u < u0 + 30; ++u)
        (*cloud) (u, v) = rayPoint (cam, u, v, z);
    return cloud;
  };
  const Cloud::Ptr near = square (5, 2.0), far = square (45, 5.0);
  Cloud::Ptr both (new Cloud (*near));
  for (std::size_t i = 0; i < both->size (); ++i)
    if (isFinite ((*far)[i]))
      (*both)[i] = (*far)[i];
  std::vector<int> expected = spurKept (near, 5), far_kept = spurKept (far, 2);
  expected.insert (expected.end (), far_kept.begin (), far_kept.end ());
  Spur filter;
  filter.setInputCloud (both);
  filter.setFocalLength (500.f);
  filter.setErosionDepth (0.02f);
  pcl::Indices kept;
  filter.filter (kept);
  EXPECT_EQ (sorted (kept), sorted (expected));
  EXPECT_EQ (filter.getPassesRun (), 5);
  // A zero erosion depth falls back to setIterations () passes everywhere.
  filter.setErosionDepth (0.f);
  filter.setIterations (3);
  filter.filter (kept);
  std::vector<int> three = spurKept (near, 3), far_three = spurKept (far, 3);
  three.insert (three.end (), far_three.begin (), far_three.end ());
  EXPECT_EQ (sorted (kept), sorted (three));
}

TEST (SpurFilter, InMetresBadParametersGiveEmptyOutput)
{
  QuietPcl quiet;
  const MetricBody body (262.5, 2.5);
  EXPECT_FALSE (metricSpurKept (body, 0.03f).empty ()) << "control";
  for (const auto &[focal, depth, width] : std::vector<std::tuple<float, float, float>>{
           {-1.f, 0.035f, 0.03f}, {nanf_ (), 0.035f, 0.03f}, {262.5f, -0.01f, 0.03f}, {262.5f, 0.035f, nanf_ ()},
           {0.f, 0.035f, 0.03f}})  // a minimum width needs a focal length
  {
    SCOPED_TRACE ("focal " + std::to_string (focal) + ", depth " + std::to_string (depth) + ", width " +
                  std::to_string (width));
    Spur filter;
    filter.setInputCloud (body.cloud);
    filter.setFocalLength (focal);
    filter.setErosionDepth (depth);
    filter.setMinWidth (width);
    pcl::Indices kept{1, 2};
    filter.filter (kept);
    EXPECT_TRUE (kept.empty ());
  }
}
}  // namespace

namespace
{
/** A slanted plane at about 4.5 m as a structured-light camera sees it: depth in steps of
  * 0.0029 z^2 (6 cm), so neighbours across a step are 6 cm apart in depth. */
Cloud::Ptr
quantisedSlopeAtFourAndAHalfMetres ()
{
  auto cloud = nanCloud (60, 40);
  for (int v = 0; v < 40; ++v)
    for (int u = 0; u < 60; ++u)
    {
      const float exact = 4.3f + 0.012f * u;  // 1.2 cm deeper per pixel: a step every ~5 pixels
      const float step = 0.0029f * exact * exact;
      const float z = step * std::round (exact / step);
      (*cloud) (u, v) = pcl::PointXYZ ((u - 30) * z / 525.f, (v - 20) * z / 525.f, z);
    }
  return cloud;
}

TEST (DepthGrowingConnectivity, AQuantisedFarSurfaceIsOneMeshAndKeepsItsPoints)
{
  const auto cloud = quantisedSlopeAtFourAndAHalfMetres ();
  // A fixed 3 cm cuts the surface at every depth step.
  Segmentation fixed;
  fixed.setInputCloud (cloud);
  fixed.setDeltaConnected (0.03f);
  std::vector<pcl::PointIndices> pieces;
  fixed.segment (pieces);
  EXPECT_GT (pieces.size (), 5u);
  // Growing with the squared depth (1.5 steps), it is one surface again.
  Segmentation growing;
  growing.setInputCloud (cloud);
  growing.setDeltaConnected (0.03f);
  growing.setDeltaConnectedGrowth (0.0043f);
  std::vector<pcl::PointIndices> meshes;
  growing.segment (meshes);
  ASSERT_EQ (meshes.size (), 1u);
  EXPECT_EQ (meshes[0].indices.size (), cloud->size ());
  // The spur filter erodes only the frame's border then, not every step's edge.
  Spur spurs;
  spurs.setInputCloud (cloud);
  spurs.setDeltaConnected (0.03f);
  spurs.setIterations (2);
  pcl::Indices kept_fixed, kept_growing;
  spurs.filter (kept_fixed);
  spurs.setDeltaConnectedGrowth (0.0043f);
  spurs.filter (kept_growing);
  EXPECT_EQ (kept_growing.size (), static_cast<std::size_t> ((60 - 4) * (40 - 4)));
  EXPECT_LT (kept_fixed.size (), kept_growing.size () / 2);
  // Near the camera the fixed delta still decides: growth 0.0043 at 2 m is 1.7 cm < 3 cm.
  EXPECT_TRUE (agex::connectedNeighbours (pcl::PointXYZ (0.f, 0.f, 2.f), pcl::PointXYZ (0.f, 0.f, 2.029f), 0.03f, 0.0043f));
  EXPECT_FALSE (agex::connectedNeighbours (pcl::PointXYZ (0.f, 0.f, 2.f), pcl::PointXYZ (0.f, 0.f, 2.031f), 0.03f, 0.0043f));
  EXPECT_TRUE (agex::connectedNeighbours (pcl::PointXYZ (0.f, 0.f, 5.f), pcl::PointXYZ (0.f, 0.f, 5.1f), 0.03f, 0.0043f));
}
}  // namespace

// ---------------------------------------------------------------------------
// One filter object for a stream of frames (as agex::DepthPipeline holds them): their
// frame-sized scratch is kept between runs and only partly refilled, so a run must give
// what a new object gives, whatever frames of whatever size came before.

namespace
{
/** Rectangles at random depths over a NaN background, ragged strands, interpolated
  * silhouette pixels and holes: everything the three filters act on. */
Cloud::Ptr
clutteredFrame (int width, int height, unsigned seed)
{
  std::mt19937 rng (seed);
  std::uniform_int_distribution<int> pick (0, 1 << 20);
  std::uniform_real_distribution<float> unit (0.f, 1.f);
  Cloud::Ptr cloud = gridCloud (width, height);
  for (int r = 0; r < 6; ++r)
  {
    const int w = 3 + pick (rng) % (width / 2), h = 3 + pick (rng) % (height / 2);
    const int u0 = pick (rng) % (width - 2), v0 = pick (rng) % (height - 2);
    fillRect (*cloud, u0, v0, std::min (w, width - u0), std::min (h, height - v0), 1.5f + 2.f * unit (rng));
  }
  for (int s = 0; s < 8; ++s)  // one-pixel strands
    fillRect (*cloud, pick (rng) % width, pick (rng) % (height - 5), 1, 5, 2.f);
  for (std::size_t i = 1; i + 1 < cloud->size (); ++i)
  {
    pcl::PointXYZ &p = (*cloud)[i];
    const pcl::PointXYZ &left = (*cloud)[i - 1], &right = (*cloud)[i + 1];
    if (unit (rng) < 0.3f && std::isfinite (left.z) && std::isfinite (right.z) && std::abs (left.z - right.z) > 0.2f)
      p = pcl::PointXYZ (p.x, p.y, 0.5f * (left.z + right.z));  // a veil pixel on a silhouette
    else if (unit (rng) < 0.05f)
      p.x = p.y = p.z = nanf_ ();
  }
  return cloud;
}

/** Every other finite point, in a scrambled order when asked. */
pcl::IndicesPtr
someIndices (const Cloud &cloud, unsigned seed, bool scrambled)
{
  pcl::IndicesPtr some (new pcl::Indices);
  for (int i = static_cast<int> (seed % 2); i < static_cast<int> (cloud.size ()); i += 2)
    some->push_back (i);
  if (scrambled)
    std::shuffle (some->begin (), some->end (), std::mt19937 (seed));
  return some;
}

pcl::IndicesPtr
allIndices (const Cloud &cloud)
{
  pcl::IndicesPtr all (new pcl::Indices (cloud.size ()));
  std::iota (all->begin (), all->end (), 0);
  return all;
}

TEST (ReusedFilters, GiveWhatNewOnesGiveFrameAfterFrame)
{
  Mixed mixed;
  mixed.setNegative (true);
  Spur spurs;
  spurs.setIterations (3);
  Segmentation segmentation;
  int mixed_found = 0, spurs_found = 0, meshes_found = 0;
  for (unsigned seed = 1; seed <= 12; ++seed)
  {
    const int width = seed % 3 == 0 ? 64 : 40, height = seed % 4 == 0 ? 48 : 30;
    const Cloud::Ptr cloud = clutteredFrame (width, height, seed);
    const bool limited = seed % 2 == 1;
    // PCL objects keep their indices: an unlimited frame is given all of them.
    const pcl::IndicesPtr some = limited ? someIndices (*cloud, seed, seed % 5 == 0) : allIndices (*cloud);
    const std::string frame = "frame " + std::to_string (seed);

    // The kept filter against a new one set up the same way.
    auto run = [&] (auto &filter) {
      filter.setInputCloud (cloud);
      filter.setIndices (some);
      pcl::Indices out;
      filter.filter (out);
      return out;
    };
    Mixed fresh_mixed;
    fresh_mixed.setNegative (true);
    const pcl::Indices mixed_expected = run (fresh_mixed);
    EXPECT_EQ (run (mixed), mixed_expected) << frame;
    mixed_found += static_cast<int> (mixed_expected.size ());

    Spur fresh_spurs;
    fresh_spurs.setIterations (3);
    const pcl::Indices spurs_expected = run (fresh_spurs);
    EXPECT_EQ (run (spurs), spurs_expected) << frame;
    spurs_found += static_cast<int> (spurs_expected.size ());

    auto run_segmentation = [&] (Segmentation &segmenter) {
      segmenter.setInputCloud (cloud);
      segmenter.setIndices (some);
      std::vector<pcl::PointIndices> meshes;
      segmenter.segment (meshes);
      std::vector<std::vector<int>> out;
      for (const auto &m : meshes)
        out.push_back (m.indices);
      return out;
    };
    Segmentation fresh_segmentation;
    const auto meshes_expected = run_segmentation (fresh_segmentation);
    EXPECT_EQ (run_segmentation (segmentation), meshes_expected) << frame;
    meshes_found += static_cast<int> (meshes_expected.size ());
    for (const auto &mesh : meshes_expected)
      EXPECT_TRUE (std::is_sorted (mesh.begin (), mesh.end ())) << frame;
  }
  // The frames did give each filter something to do.
  EXPECT_GT (mixed_found, 20);
  EXPECT_GT (spurs_found, 100);
  EXPECT_GT (meshes_found, 24);
}

TEST (SurfaceSegmentation, ScrambledIndicesGiveTheSameMeshes)
{
  const Cloud::Ptr cloud = clutteredFrame (40, 30, 99);
  const pcl::IndicesPtr in_order = someIndices (*cloud, 99, false), scrambled = someIndices (*cloud, 99, true);
  ASSERT_NE (*in_order, *scrambled);
  Segmentation a, b;
  a.setInputCloud (cloud);
  a.setIndices (in_order);
  b.setInputCloud (cloud);
  b.setIndices (scrambled);
  std::vector<pcl::PointIndices> meshes_a, meshes_b;
  a.segment (meshes_a);
  b.segment (meshes_b);
  ASSERT_GT (meshes_a.size (), 2u);
  ASSERT_EQ (meshes_a.size (), meshes_b.size ());
  for (std::size_t m = 0; m < meshes_a.size (); ++m)
    EXPECT_EQ (meshes_a[m].indices, meshes_b[m].indices) << m;
}
}  // namespace

// agex::AGEXKeypoint: the incremental Dijkstra gives exactly the naive result,
// analytic synthetic figures (stars, several blobs, holes) give the expected
// extrema and orientations, and bad input never crashes.

#include "test_support.h"

#include <agex/filters/surface_segmentation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/common/io.h>
#include <pcl/console/print.h>

#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>

namespace
{
using namespace agex_test;
using Agex = agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint>;
using IPCloud = pcl::PointCloud<agex::InterestPoint>;


struct AgexRun
{
  IPCloud points;
  std::vector<int> indices;
  std::vector<pcl::PointIndices> meshes;
};

AgexRun
runAgex (const Cloud::ConstPtr &cloud, int k, std::size_t min_mesh, Agex::Mode mode,
         const std::vector<pcl::PointIndices> *meshes = nullptr, float delta_orient = 0.10f, float min_separation = 0.f)
{
  Agex agex;
  agex.setInputCloud (cloud);
  agex.setPointsPerMesh (k);
  agex.setMinSeparation (min_separation);
  agex.setMinMeshSize (min_mesh);
  agex.setDeltaOrient (delta_orient);
  agex.setMode (mode);
  if (meshes)
    agex.setMeshes (*meshes);
  AgexRun run;
  agex.compute (run.points);
  run.indices.assign (agex.getKeypointsIndices ()->indices.begin (), agex.getKeypointsIndices ()->indices.end ());
  run.meshes = agex.getMeshes ();
  return run;
}

/** Checks that two AGEX runs agree bit for bit; returns the number of points whose
  * orientation differs (reported separately so a tie-only difference is visible). */
void
expectBitwiseEqual (const AgexRun &a, const AgexRun &b)
{
  ASSERT_EQ (a.points.size (), b.points.size ());
  ASSERT_EQ (a.indices, b.indices);
  ASSERT_EQ (a.meshes.size (), b.meshes.size ());
  for (std::size_t m = 0; m < a.meshes.size (); ++m)
    EXPECT_EQ (a.meshes[m].indices, b.meshes[m].indices) << "mesh " << m;
  int orientation_mismatches = 0;
  for (std::size_t i = 0; i < a.points.size (); ++i)
  {
    const agex::InterestPoint &p = a.points[i], &q = b.points[i];
    SCOPED_TRACE ("interest point " + std::to_string (i) + " (mesh " + std::to_string (p.mesh) + ", rank " +
                  std::to_string (p.rank) + ")");
    EXPECT_EQ (bits (p.x), bits (q.x));
    EXPECT_EQ (bits (p.y), bits (q.y));
    EXPECT_EQ (bits (p.z), bits (q.z));
    EXPECT_EQ (bits (p.geodesic_distance), bits (q.geodesic_distance))
        << p.geodesic_distance << " vs " << q.geodesic_distance;
    EXPECT_EQ (p.rank, q.rank);
    EXPECT_EQ (p.mesh, q.mesh);
    EXPECT_EQ (p.u, q.u);
    EXPECT_EQ (p.v, q.v);
    bool same_orientation = true;
    for (int c = 0; c < 3; ++c)
      same_orientation = same_orientation && bits (p.orientation[c]) == bits (q.orientation[c]);
    if (!same_orientation)
      ++orientation_mismatches;
    EXPECT_TRUE (same_orientation) << "orientation (" << p.orientation[0] << ", " << p.orientation[1] << ", "
                                   << p.orientation[2] << ") vs (" << q.orientation[0] << ", " << q.orientation[1]
                                   << ", " << q.orientation[2] << ")";
  }
  EXPECT_EQ (orientation_mismatches, 0) << "orientations differ between the modes on " << orientation_mismatches
                                        << " of " << a.points.size () << " points";
}

/** Properties every AGEX output has, whatever the scene. */
void
expectWellFormed (const Cloud &cloud, const AgexRun &run, int k)
{
  ASSERT_EQ (run.points.size (), run.indices.size ());
  std::map<int, int> next_rank;  // mesh -> expected next rank
  std::set<int> seen;
  float previous_distance = 0.f;
  for (std::size_t i = 0; i < run.points.size (); ++i)
  {
    const agex::InterestPoint &p = run.points[i];
    SCOPED_TRACE ("interest point " + std::to_string (i));
    const int index = run.indices[i];
    EXPECT_TRUE (seen.insert (index).second) << "index " << index << " found twice";
    EXPECT_EQ (p.u, index % static_cast<int> (cloud.width));
    EXPECT_EQ (p.v, index / static_cast<int> (cloud.width));
    EXPECT_EQ (p.x, cloud[index].x);
    EXPECT_EQ (p.y, cloud[index].y);
    EXPECT_EQ (p.z, cloud[index].z);
    const int expected_rank = next_rank.count (p.mesh) ? next_rank[p.mesh] : 1;
    EXPECT_EQ (p.rank, expected_rank);
    EXPECT_LE (p.rank, k);
    next_rank[p.mesh] = p.rank + 1;
    ASSERT_GE (p.mesh, 0);
    ASSERT_LT (static_cast<std::size_t> (p.mesh), run.meshes.size ());
    const auto &mesh = run.meshes[p.mesh].indices;
    EXPECT_TRUE (std::find (mesh.begin (), mesh.end (), index) != mesh.end ()) << "point outside its mesh";
    const float norm = Eigen::Vector3f (p.orientation[0], p.orientation[1], p.orientation[2]).norm ();
    if (p.rank == 1)
    {
      EXPECT_EQ (p.geodesic_distance, 0.f);
      EXPECT_EQ (norm, 0.f);
    }
    else
    {
      EXPECT_GT (p.geodesic_distance, 0.f);
      EXPECT_NEAR (norm, 1.f, 1e-5f);
      // Adding sources only shortens distances, so each new maximum is no larger.
      if (p.rank > 2)
      {
        EXPECT_LE (p.geodesic_distance, previous_distance);
      }
    }
    previous_distance = p.geodesic_distance;
  }
}

/** A random smooth height field seen by a 120x90 pinhole camera, with random NaN
  * holes and speckle; split adds a 0.3 m depth step and a NaN band, so that it
  * falls into several meshes. */
Cloud::Ptr
randomHeightField (unsigned seed, bool split)
{
  std::mt19937 rng (seed);
  std::uniform_real_distribution<double> uni (0.0, 1.0);
  Camera cam;
  cam.width = 120;
  cam.height = 90;
  cam.fx = cam.fy = 262.5;
  cam.cx = 59.5;
  cam.cy = 44.5;
  struct Wave
  {
    double a, fu, pu, fv, pv;
  };
  std::vector<Wave> waves (4);
  for (auto &w : waves)
    w = {0.02 + 0.06 * uni (rng), 0.02 + 0.10 * uni (rng), 6.3 * uni (rng), 0.02 + 0.10 * uni (rng), 6.3 * uni (rng)};
  const int step_u = 40 + static_cast<int> (40 * uni (rng));
  const int band_v = 30 + static_cast<int> (30 * uni (rng));

  Cloud::Ptr cloud = nanCloud (cam.width, cam.height);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
    {
      double z = 2.0;
      for (const auto &w : waves)
        z += w.a * std::sin (w.fu * u + w.pu) * std::cos (w.fv * v + w.pv);
      if (split && u > step_u)
        z += 0.3;
      if (split && v >= band_v && v < band_v + 2)
        continue;
      if (uni (rng) < 0.03)
        continue;  // speckle
      (*cloud) (u, v) = rayPoint (cam, u, v, z);
    }
  const int holes = 8 + static_cast<int> (8 * uni (rng));
  for (int h = 0; h < holes; ++h)
  {
    const double hu = cam.width * uni (rng), hv = cam.height * uni (rng), r = 1.0 + 5.0 * uni (rng);
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u)
        if ((u - hu) * (u - hu) + (v - hv) * (v - hv) <= r * r)
          (*cloud) (u, v) = nanPoint ();
  }
  return cloud;
}

// ---------------------------------------------------------------------------
// 1. Incremental == naive

TEST (AgexIncrementalVsNaive, RandomHeightFieldsAreBitwiseEqual)
{
  int split_scenes_with_several_meshes = 0;
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u})
  {
    const bool split = seed % 2 == 0;
    SCOPED_TRACE ("seed " + std::to_string (seed) + (split ? " (split)" : ""));
    const Cloud::Ptr cloud = randomHeightField (seed, split);
    const AgexRun inc = runAgex (cloud, 12, 30, Agex::Mode::Incremental);
    const AgexRun naive = runAgex (cloud, 12, 30, Agex::Mode::Naive);
    ASSERT_FALSE (inc.points.empty ());
    expectBitwiseEqual (inc, naive);
    expectWellFormed (*cloud, inc, 12);
    if (split && inc.meshes.size () >= 3)
      ++split_scenes_with_several_meshes;
  }
  // The split scenes must really exercise the multi-mesh path.
  EXPECT_GE (split_scenes_with_several_meshes, 3);
}

TEST (AgexIncrementalVsNaive, ExactTiesOnADyadicGridAreBitwiseEqual)
{
  // Coordinates that are exact in binary make many path lengths tie exactly, which
  // is where a careless incremental update would pick other parents or points.
  for (unsigned seed : {11u, 12u, 13u})
  {
    SCOPED_TRACE ("seed " + std::to_string (seed));
    std::mt19937 rng (seed);
    std::uniform_int_distribution<int> pick (0, 99);
    Cloud::Ptr cloud = nanCloud (64, 48);
    for (int v = 0; v < 48; ++v)
      for (int u = 0; u < 64; ++u)
        if (pick (rng) >= 8)
          (*cloud) (u, v) = pcl::PointXYZ ((u - 32) / 256.f, (v - 24) / 256.f,
                                           2.f + (seed == 13u ? static_cast<float> (u % 4) / 256.f : 0.f));
    for (int k : {3, 9, 25})
    {
      SCOPED_TRACE ("k " + std::to_string (k));
      const AgexRun inc = runAgex (cloud, k, 10, Agex::Mode::Incremental, nullptr, 0.03f);
      const AgexRun naive = runAgex (cloud, k, 10, Agex::Mode::Naive, nullptr, 0.03f);
      ASSERT_FALSE (inc.points.empty ());
      expectBitwiseEqual (inc, naive);
      expectWellFormed (*cloud, inc, k);
    }
  }
}

TEST (AgexIncrementalVsNaive, UserMeshesAndOtherPointTypes)
{
  const Cloud::Ptr cloud = randomHeightField (21, true);
  agex::SurfaceSegmentation<pcl::PointXYZ> seg;
  seg.setInputCloud (cloud);
  seg.setMinMeshSize (30);
  std::vector<pcl::PointIndices> meshes;
  seg.segment (meshes);
  ASSERT_GE (meshes.size (), 2u);
  const AgexRun own = runAgex (cloud, 7, 30, Agex::Mode::Incremental);
  const AgexRun inc = runAgex (cloud, 7, 30, Agex::Mode::Incremental, &meshes);
  const AgexRun naive = runAgex (cloud, 7, 30, Agex::Mode::Naive, &meshes);
  expectBitwiseEqual (inc, naive);
  // Meshes from SurfaceSegmentation are exactly the ones AGEX finds by itself.
  expectBitwiseEqual (own, inc);

  // PointXYZI in, PointXYZ out: the same positions and indices.
  pcl::PointCloud<pcl::PointXYZI>::Ptr xyzi (new pcl::PointCloud<pcl::PointXYZI>);
  pcl::copyPointCloud (*cloud, *xyzi);
  agex::AGEXKeypoint<pcl::PointXYZI, pcl::PointXYZ> other;
  other.setInputCloud (xyzi);
  other.setPointsPerMesh (7);
  other.setMinMeshSize (30);
  pcl::PointCloud<pcl::PointXYZ> out;
  other.compute (out);
  ASSERT_EQ (out.size (), inc.points.size ());
  EXPECT_EQ (other.getKeypointsIndices ()->indices, inc.indices);
  for (std::size_t i = 0; i < out.size (); ++i)
  {
    EXPECT_EQ (bits (out[i].x), bits (inc.points[i].x));
    EXPECT_EQ (bits (out[i].y), bits (inc.points[i].y));
    EXPECT_EQ (bits (out[i].z), bits (inc.points[i].z));
  }
}

// ---------------------------------------------------------------------------
// 2. Analytic scenes

double
angleDeg (const Eigen::Vector3f &a, const Eigen::Vector3f &b)
{
  const double c = a.normalized ().dot (b.normalized ());
  return std::acos (std::clamp (c, -1.0, 1.0)) * 180.0 / M_PI;
}

/** Checks that the interest points of one mesh are: rank 1 near the figure's
  * centre, ranks 2..limbs+1 on distinct limb tips with outward orientations; the
  * orientation errors (degrees) are appended to angles. */
void
expectFigureFound (const IPCloud &points, int mesh, const Figure &figure, double tip_tolerance,
                   double max_angle_deg, std::vector<double> &angles, std::ostream *log = nullptr)
{
  std::vector<agex::InterestPoint> mine;
  for (const auto &p : points)
    if (p.mesh == mesh)
      mine.push_back (p);
  const std::size_t n = figure.limbs.size ();
  ASSERT_GE (mine.size (), n + 1);
  EXPECT_EQ (mine[0].rank, 1);
  const double centre_error = (mine[0].getVector3fMap () - figure.centre3D ()).norm ();
  EXPECT_LT (centre_error, 0.015) << "rank 1 should be the figure's centre";
  if (log)
    *log << "mesh " << mesh << ": centre error " << centre_error * 100 << " cm\n";
  std::set<std::size_t> tips_found;
  for (std::size_t r = 1; r <= n; ++r)
  {
    const agex::InterestPoint &p = mine[r];
    std::size_t nearest = 0;
    double best = 1e9;
    for (std::size_t l = 0; l < n; ++l)
    {
      const double d = (p.getVector3fMap () - figure.tip3D (l)).norm ();
      if (d < best)
      {
        best = d;
        nearest = l;
      }
    }
    const Eigen::Vector3f limb_dir (static_cast<float> (figure.limbs[nearest].direction.x ()),
                                    static_cast<float> (figure.limbs[nearest].direction.y ()), 0.f);
    const double angle = angleDeg (p.getOrientationVector3fMap (), limb_dir);
    angles.push_back (angle);
    if (log)
      *log << "mesh " << mesh << " rank " << p.rank << ": limb " << nearest << ", tip error " << best * 100
           << " cm, orientation error " << angle << " deg\n";
    EXPECT_LT (best, tip_tolerance) << "rank " << p.rank << " is not on a limb tip";
    EXPECT_TRUE (tips_found.insert (nearest).second) << "limb " << nearest << " found twice";
    EXPECT_LT (angle, max_angle_deg) << "rank " << p.rank << " orientation does not point along limb " << nearest;
  }
  EXPECT_EQ (tips_found.size (), n);
}

// Orientation accuracy. The orientation is unit(tip - v), v being the vertex reached
// by following the shortest-path tree back 10 cm (delta_orient). Shortest paths on
// the 8-connected pixel grid are not straight: a limb at an angle to the grid is
// walked as some mix of axial and diagonal steps in no particular order, so over a
// 10 cm (~26 px at 2 m) prefix v can sit several pixels off the limb's axis. On
// these clean straight limbs that costs up to ~20 degrees (measured maximum 19.7
// over 30 limbs at 6 rotations) while the typical error is a few degrees (mean
// ~8). Hence: every orientation within kMaxOrientationErrorDeg, and the mean over
// all limbs within kMeanOrientationErrorDeg.
constexpr double kMaxOrientationErrorDeg = 25.0;
constexpr double kMeanOrientationErrorDeg = 10.0;

double
mean (const std::vector<double> &values)
{
  double sum = 0.0;
  for (const double v : values)
    sum += v;
  return values.empty () ? 0.0 : sum / values.size ();
}

TEST (AgexSynthetic, StarLimbTipsCentreAndOrientations)
{
  const Camera cam;  // 320x240, f = 525
  std::vector<double> angles;
  // Several rotations, so that limbs run at many angles to the pixel grid.
  for (double first_angle : {-90.0, -77.0, -63.0, -45.0, -31.0, 7.0})
  {
    std::ostringstream log;
    SCOPED_TRACE ("first limb at " + std::to_string (first_angle) + " deg");
    const Figure star = makeStar (Eigen::Vector2d::Zero (), 2.0, 5, 0.28, 0.025, 0.08, first_angle);
    const Cloud::Ptr cloud = rasterise ({star}, cam);
    const AgexRun run = runAgex (cloud, 6, 50, Agex::Mode::Incremental);
    ASSERT_EQ (run.meshes.size (), 1u);
    ASSERT_EQ (run.points.size (), 6u);
    expectWellFormed (*cloud, run, 6);
    expectFigureFound (run.points, 0, star, 0.03, kMaxOrientationErrorDeg, angles, &log);
    std::cout << "[ star " << first_angle << " deg ]\n" << log.str ();
  }
  ASSERT_EQ (angles.size (), 30u);
  EXPECT_LT (mean (angles), kMeanOrientationErrorDeg);
  std::cout << "mean orientation error " << mean (angles) << " deg, max "
            << *std::max_element (angles.begin (), angles.end ()) << " deg\n";
}

/** Two separate stars: a five-limbed one at 2 m on the left (mesh 0), a three-limbed one at
  * 2.4 m on the right (mesh 1). */
struct TwoStars
{
  const Figure big = makeStar (Eigen::Vector2d (-0.30, 0.0), 2.0, 5, 0.18, 0.022, 0.06, -90.0);
  const Figure small = makeStar (Eigen::Vector2d (0.33, 0.02), 2.4, 3, 0.12, 0.022, 0.05, -60.0);
  const Cloud::Ptr cloud = rasterise ({big, small}, Camera ());
};

TEST (AgexSynthetic, TwoBlobsGetTwoMeshesWithTheirOwnPoints)
{
  const TwoStars stars;
  const AgexRun run = runAgex (stars.cloud, 6, 50, Agex::Mode::Incremental);
  ASSERT_EQ (run.meshes.size (), 2u);
  EXPECT_GT (run.meshes[0].indices.size (), run.meshes[1].indices.size ()) << "meshes are sorted largest first";
  ASSERT_EQ (run.points.size (), 12u);
  expectWellFormed (*stars.cloud, run, 6);
  for (const auto &p : run.points)
  {
    // Mesh 0 is the big star on the left, mesh 1 the small one on the right.
    if (p.mesh == 0)
      EXPECT_LT (p.x, -0.05f) << "rank " << p.rank;
    else
      EXPECT_GT (p.x, 0.05f) << "rank " << p.rank;
  }
  std::vector<double> angles;
  expectFigureFound (run.points, 0, stars.big, 0.03, kMaxOrientationErrorDeg, angles);
  expectFigureFound (run.points, 1, stars.small, 0.03, kMaxOrientationErrorDeg, angles);
  EXPECT_LT (mean (angles), kMeanOrientationErrorDeg);
}

TEST (AgexSynthetic, MinSeparationStopsEachMeshAtItsExtremities)
{
  const TwoStars stars;
  const AgexRun all = runAgex (stars.cloud, 16, 50, Agex::Mode::Incremental);
  ASSERT_EQ (all.points.size (), 32u);
  // Geodesically the tips lie 0.14-0.22 m from the centre (the surface and the pixel grid
  // lengthen the 0.18 and 0.12 m limbs); a limb's middle is at most 0.11 m from its tip and
  // the centre.
  constexpr float kSeparation = 0.13f;
  for (const auto mode : {Agex::Mode::Incremental, Agex::Mode::Naive})
  {
    const AgexRun run = runAgex (stars.cloud, 16, 50, mode, nullptr, 0.10f, kSeparation);
    ASSERT_EQ (run.meshes.size (), 2u);
    // The centroid and one point per limb tip: 6 on the five-limbed star, 4 on the other.
    std::size_t per_mesh[2] = {0, 0};
    for (const auto &p : run.points)
      ++per_mesh[p.mesh];
    EXPECT_EQ (per_mesh[0], 6u);
    EXPECT_EQ (per_mesh[1], 4u);
    // Each mesh's points are the first ones of the run without the limit, and the first
    // point left out is closer than the limit to those kept.
    std::size_t i = 0;
    for (std::size_t j = 0; j < all.points.size (); ++j)
    {
      const auto &p = all.points[j];
      if (static_cast<std::size_t> (p.rank) <= per_mesh[p.mesh])
      {
        ASSERT_LT (i, run.points.size ());
        EXPECT_EQ (run.indices[i], all.indices[j]);
        EXPECT_EQ (run.points[i].rank, p.rank);
        if (p.rank > 1)
          EXPECT_GE (run.points[i].geodesic_distance, kSeparation);
        ++i;
      }
      else if (static_cast<std::size_t> (p.rank) == per_mesh[p.mesh] + 1)
        EXPECT_LT (p.geodesic_distance, kSeparation) << "mesh " << p.mesh;
    }
    EXPECT_EQ (i, run.points.size ());
    std::vector<double> angles;
    expectFigureFound (run.points, 0, stars.big, 0.03, kMaxOrientationErrorDeg, angles);
    expectFigureFound (run.points, 1, stars.small, 0.03, kMaxOrientationErrorDeg, angles);
  }
}

TEST (AgexSynthetic, HolesInTheFigureStillGiveTheTips)
{
  const Camera cam;
  const Figure star = makeStar (Eigen::Vector2d::Zero (), 2.0, 5, 0.28, 0.025, 0.08, -90.0);
  const Cloud::Ptr cloud = rasterise ({star}, cam);
  std::mt19937 rng (7);
  std::uniform_int_distribution<int> pu (0, cam.width - 1), pv (0, cam.height - 1);
  int punched = 0;
  while (punched < 80)
  {
    const int u = pu (rng), v = pv (rng);
    if (!isFinite ((*cloud) (u, v)))
      continue;
    for (int dv = 0; dv < 2; ++dv)  // 2x2 holes
      for (int du = 0; du < 2; ++du)
        if (u + du < cam.width && v + dv < cam.height)
          (*cloud) (u + du, v + dv) = nanPoint ();
    ++punched;
  }
  const AgexRun run = runAgex (cloud, 6, 50, Agex::Mode::Incremental);
  ASSERT_EQ (run.meshes.size (), 1u);
  ASSERT_EQ (run.points.size (), 6u);
  expectWellFormed (*cloud, run, 6);
  // Paths now detour around the holes, so only the per-limb bound applies here
  // (a mean over 5 limbs says little).
  std::vector<double> angles;
  std::ostringstream log;
  expectFigureFound (run.points, 0, star, 0.03, kMaxOrientationErrorDeg, angles, &log);
  std::cout << log.str ();
  expectBitwiseEqual (run, runAgex (cloud, 6, 50, Agex::Mode::Naive));
}

// ---------------------------------------------------------------------------
// 7. Bad input never crashes

TEST (AgexBadInput, UnorganizedCloudGivesEmptyOutput)
{
  QuietPcl quiet;
  Cloud::Ptr cloud (new Cloud);
  for (int i = 0; i < 500; ++i)
    cloud->push_back (pcl::PointXYZ (0.004f * (i % 25), 0.004f * (i / 25), 2.f));
  ASSERT_FALSE (cloud->isOrganized ());
  Agex agex;
  agex.setInputCloud (cloud);
  agex.setMinMeshSize (1);
  IPCloud out;
  agex.compute (out);
  EXPECT_TRUE (out.empty ());
  EXPECT_TRUE (agex.getKeypointsIndices ()->indices.empty ());
}

TEST (AgexBadInput, AFailedRunThroughTheBaseClassLeavesNoStaleIndices)
{
  QuietPcl quiet;
  Agex agex;
  agex.setInputCloud (randomHeightField (3, false));
  agex.setMinMeshSize (1);
  IPCloud out;
  pcl::Keypoint<pcl::PointXYZ, agex::InterestPoint> &base = agex;
  base.compute (out);
  ASSERT_FALSE (agex.getKeypointsIndices ()->indices.empty ());  // control: a good run
  Cloud::Ptr unorganized (new Cloud);
  for (int i = 0; i < 500; ++i)
    unorganized->push_back (pcl::PointXYZ (0.004f * (i % 25), 0.004f * (i / 25), 2.f));
  agex.setInputCloud (unorganized);
  base.compute (out);  // pcl::Keypoint::compute is not virtual: the reset must be in initCompute
  EXPECT_TRUE (agex.getKeypointsIndices ()->indices.empty ());
}

TEST (AgexBadInput, EmptyAndAllNanCloudsGiveEmptyOutput)
{
  QuietPcl quiet;
  for (const Cloud::Ptr &cloud : {Cloud::Ptr (new Cloud), nanCloud (64, 48), nanCloud (640, 480)})
  {
    SCOPED_TRACE (std::to_string (cloud->width) + "x" + std::to_string (cloud->height));
    for (auto mode : {Agex::Mode::Incremental, Agex::Mode::Naive})
    {
      const AgexRun run = runAgex (cloud, 5, 1, mode);
      EXPECT_TRUE (run.points.empty ());
      EXPECT_TRUE (run.indices.empty ());
      EXPECT_TRUE (run.meshes.empty ());
    }
  }
}

TEST (AgexBadInput, KLargerThanTheMesh)
{
  Cloud::Ptr cloud = nanCloud (10, 10);
  (*cloud) (4, 4) = pcl::PointXYZ (0.f, 0.f, 2.f);
  (*cloud) (5, 4) = pcl::PointXYZ (0.004f, 0.f, 2.f);
  (*cloud) (5, 5) = pcl::PointXYZ (0.004f, 0.004f, 2.f);
  for (auto mode : {Agex::Mode::Incremental, Agex::Mode::Naive})
  {
    const AgexRun run = runAgex (cloud, 10, 1, mode);
    ASSERT_EQ (run.points.size (), 3u);
    expectWellFormed (*cloud, run, 10);
    EXPECT_EQ (std::set<int> (run.indices.begin (), run.indices.end ()).size (), 3u);
  }
  // The default minimum mesh size (50) skips so small a mesh.
  Agex agex;
  agex.setInputCloud (cloud);
  IPCloud out;
  agex.compute (out);
  EXPECT_TRUE (out.empty ());
}

TEST (AgexBadInput, OnePixelMesh)
{
  Cloud::Ptr cloud = nanCloud (8, 8);
  (*cloud) (3, 2) = pcl::PointXYZ (0.1f, 0.2f, 1.5f);
  const AgexRun run = runAgex (cloud, 5, 1, Agex::Mode::Incremental);
  ASSERT_EQ (run.points.size (), 1u);
  EXPECT_EQ (run.points[0].rank, 1);
  EXPECT_EQ (run.points[0].u, 3);
  EXPECT_EQ (run.points[0].v, 2);
  EXPECT_EQ (run.points[0].z, 1.5f);
  EXPECT_EQ (run.indices, std::vector<int> ({2 * 8 + 3}));
}

TEST (AgexBadInput, UserMeshesWithDuplicatesNanAndBadIndices)
{
  QuietPcl quiet;
  Cloud::Ptr cloud = nanCloud (10, 10);
  for (int u = 2; u < 6; ++u)
    (*cloud) (u, 3) = pcl::PointXYZ (0.004f * u, 0.f, 2.f);
  // Duplicates and a NaN pixel in a user mesh: each point at most once.
  std::vector<pcl::PointIndices> meshes (1);
  meshes[0].indices = {32, 33, 33, 34, 35, 32, 0};
  AgexRun run = runAgex (cloud, 10, 1, Agex::Mode::Incremental, &meshes);
  EXPECT_EQ (run.points.size (), 4u);
  EXPECT_EQ (std::set<int> (run.indices.begin (), run.indices.end ()).size (), run.indices.size ());
  // An index outside the cloud is an error: empty output, no crash.
  meshes[0].indices = {32, 33, 1000};
  run = runAgex (cloud, 10, 1, Agex::Mode::Incremental, &meshes);
  EXPECT_TRUE (run.points.empty ());
  meshes[0].indices = {-1, 32};
  run = runAgex (cloud, 10, 1, Agex::Mode::Incremental, &meshes);
  EXPECT_TRUE (run.points.empty ());
}

TEST (AgexBadInput, InvalidParametersGiveEmptyOutput)
{
  QuietPcl quiet;
  const Cloud::Ptr cloud = randomHeightField (3, false);
  EXPECT_TRUE (runAgex (cloud, 0, 1, Agex::Mode::Incremental).points.empty ());
  EXPECT_TRUE (runAgex (cloud, -3, 1, Agex::Mode::Naive).points.empty ());
  EXPECT_TRUE (runAgex (cloud, 5, 1, Agex::Mode::Incremental, nullptr, -1.f).points.empty ());
  EXPECT_TRUE (runAgex (cloud, 5, 1, Agex::Mode::Incremental, nullptr, 0.1f, -0.01f).points.empty ());
  const float nan = std::numeric_limits<float>::quiet_NaN (), inf = std::numeric_limits<float>::infinity ();
  EXPECT_TRUE (runAgex (cloud, 5, 1, Agex::Mode::Incremental, nullptr, 0.1f, nan).points.empty ());
  EXPECT_TRUE (runAgex (cloud, 5, 1, Agex::Mode::Naive, nullptr, 0.1f, inf).points.empty ());
  EXPECT_FALSE (runAgex (cloud, 5, 1, Agex::Mode::Incremental).points.empty ());  // control
}
}  // namespace

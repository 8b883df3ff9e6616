// agex::DepthMedianFilter: bit for bit pcl::MedianFilter's depths on random organized
// clouds (NaN holes, borders, clamped moves), the viewing-ray option, setIndices and
// misuse (unorganized input, bad parameters) the PCL way.

#include "test_support.h"

#include <agex/filters/depth_median_filter.h>

#include <pcl/filters/median_filter.h>

#include <random>

namespace
{
using namespace agex_test;
using Median = agex::DepthMedianFilter<pcl::PointXYZ>;

/** A width x height depth frame seen through a pinhole camera: depth in 8-bit steps of
  * 0.016 m (as the Bonn frames, so windows hold ties) on a slope with random bumps and
  * jumps, about a fifth of the pixels NaN and a few with only x or only z invalid. */
Cloud::Ptr
randomFrame (int width, int height, unsigned seed)
{
  std::mt19937 rng (seed);
  std::uniform_real_distribution<double> unit (0.0, 1.0);
  Camera cam;
  cam.width = width;
  cam.height = height;
  cam.cx = (width - 1) / 2.0;
  cam.cy = (height - 1) / 2.0;
  cam.fx = cam.fy = 100.0;
  Cloud::Ptr cloud = nanCloud (width, height);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const double r = unit (rng);
      if (r < 0.2)
        continue;
      double z = 1.5 + 0.01 * u + 0.2 * unit (rng) + (unit (rng) < 0.1 ? 0.8 : 0.0);
      z = 0.016 * std::round (z / 0.016);
      pcl::PointXYZ p = rayPoint (cam, u, v, z);
      if (r > 0.99)
        p.x = nanf_ ();  // not a finite point for PCL, though z is
      else if (r > 0.98)
        p.z = std::numeric_limits<float>::infinity ();
      (*cloud) (u, v) = p;
    }
  return cloud;
}

Cloud
pclMedian (const Cloud::Ptr &input, int window, float max_movement)
{
  pcl::MedianFilter<pcl::PointXYZ> median;
  median.setInputCloud (input);
  median.setWindowSize (window);
  median.setMaxAllowedMovement (max_movement);
  Cloud out;
  median.filter (out);
  return out;
}

Cloud
agexMedian (const Cloud::Ptr &input, int window, float max_movement, bool keep_on_ray)
{
  Median median;
  median.setInputCloud (input);
  median.setWindowSize (window);
  median.setMaxAllowedMovement (max_movement);
  median.setKeepOnViewingRay (keep_on_ray);
  Cloud out;
  median.filter (out);
  return out;
}

void
expectBitwiseEqual (const Cloud &expected, const Cloud &actual, const std::string &what)
{
  ASSERT_EQ (expected.width, actual.width) << what;
  ASSERT_EQ (expected.height, actual.height) << what;
  int differences = 0;
  for (std::size_t i = 0; i < expected.size (); ++i)
    if (bits (expected[i].x) != bits (actual[i].x) || bits (expected[i].y) != bits (actual[i].y) ||
        bits (expected[i].z) != bits (actual[i].z))
    {
      if (++differences <= 5)
        ADD_FAILURE () << what << ": point " << i << " (" << i % expected.width << ", " << i / expected.width
                       << ") expected " << expected[i] << ", got " << actual[i];
    }
  EXPECT_EQ (differences, 0) << what;
}

const float kMaxMovements[] = {0.01f, 0.05f, 0.3f, std::numeric_limits<float>::max ()};

TEST (DepthMedianFilter, SameCloudAsPclMedianFilter)
{
  int moved = 0, clamped = 0;
  for (const auto &[width, height] : {std::pair (23, 17), std::pair (8, 2), std::pair (1, 9), std::pair (2, 2)})
    for (unsigned seed : {1u, 2u, 3u})
    {
      const Cloud::Ptr input = randomFrame (width, height, seed);
      for (int window : {3, 5, 1, 4, 7})
        for (float max_movement : kMaxMovements)
        {
          const std::string what = std::to_string (width) + "x" + std::to_string (height) + " seed " +
                                   std::to_string (seed) + " window " + std::to_string (window) + " max " +
                                   std::to_string (max_movement);
          const Cloud expected = pclMedian (input, window, max_movement);
          expectBitwiseEqual (expected, agexMedian (input, window, max_movement, false), what);
          for (std::size_t i = 0; i < input->size (); ++i)
          {
            const float step = std::abs (expected[i].z - (*input)[i].z);
            moved += step > 0.f;
            clamped += step > 0.f && std::abs (step - max_movement) < 1e-5f;
          }
        }
    }
  // The comparison covered real work: depths that moved, some by exactly the limit.
  EXPECT_GT (moved, 1000);
  EXPECT_GT (clamped, 50);
}

TEST (DepthMedianFilter, SampleSpacingIsTheMedianOfTheSubsampledFrame)
{
  // With samples s pixels apart, the median at (u, v) is the plain median, at (u / s, v / s),
  // of the frame's pixels (u mod s + s i, v mod s + s j): the same depths bit for bit.
  int compared = 0;
  for (unsigned seed : {4u, 5u})
  {
    const Cloud::Ptr input = randomFrame (29, 22, seed);
    for (const int spacing : {2, 3})
      for (const int window : {3, 5})
      {
        Median median;
        median.setInputCloud (input);
        median.setWindowSize (window);
        median.setSampleSpacing (spacing);
        median.setMaxAllowedMovement (0.05f);
        median.setKeepOnViewingRay (false);
        Cloud spaced;
        median.filter (spaced);
        ASSERT_EQ (spaced.size (), input->size ());
        for (int phase_v = 0; phase_v < spacing; ++phase_v)
          for (int phase_u = 0; phase_u < spacing; ++phase_u)
          {
            const int w = (static_cast<int> (input->width) - phase_u + spacing - 1) / spacing;
            const int h = (static_cast<int> (input->height) - phase_v + spacing - 1) / spacing;
            Cloud::Ptr sub (new Cloud (w, h));
            for (int j = 0; j < h; ++j)
              for (int i = 0; i < w; ++i)
                (*sub) (i, j) = (*input) (phase_u + spacing * i, phase_v + spacing * j);
            const Cloud expected = agexMedian (sub, window, 0.05f, false);
            for (int j = 0; j < h; ++j)
              for (int i = 0; i < w; ++i)
              {
                const auto &a = expected (i, j), &b = spaced (phase_u + spacing * i, phase_v + spacing * j);
                EXPECT_EQ (bits (a.z), bits (b.z)) << "spacing " << spacing << " window " << window << " at ("
                                                   << phase_u + spacing * i << ", " << phase_v + spacing * j << ")";
                compared += std::isfinite (a.z);
              }
          }
      }
  }
  EXPECT_GT (compared, 3000);
  // A spacing outside 1-kMaxSpacing is refused.
  QuietPcl quiet;
  Median median;
  median.setInputCloud (randomFrame (10, 10, 1));
  median.setWindowSize (3);
  Cloud out;
  for (const int bad : {0, -1, Median::kMaxSpacing + 1})
  {
    median.setSampleSpacing (bad);
    median.filter (out);
    EXPECT_TRUE (out.empty ()) << bad;
  }
}

/** A width x height cloud with the given depths (NaN: an invalid pixel) on x = y = 0. */
Cloud::Ptr
depthCloud (int width, int height, const std::vector<float> &depths)
{
  Cloud::Ptr cloud = nanCloud (width, height);
  for (std::size_t i = 0; i < depths.size (); ++i)
    if (!std::isnan (depths[i]))
      (*cloud)[i] = pcl::PointXYZ (0.f, 0.f, depths[i]);
  return cloud;
}

TEST (DepthMedianFilter, EveryThreeByThreeWindowOfTwoDepthsAndHoles)
{
  // Every 3x3 window over {NaN, 1, 2} with a valid centre: every count of valid
  // neighbours and, by the 0-1 principle of comparison networks, every ordering.
  const float values[3] = {nanf_ (), 1.f, 2.f};
  int patterns = 0, moved = 0;
  std::vector<float> depths (9);
  for (int code = 0; code < 6561 * 2; ++code)
  {
    int rest = code;
    for (int i = 0; i < 9; ++i)
    {
      if (i == 4)
      {
        depths[i] = values[1 + rest % 2];
        rest /= 2;
      }
      else
      {
        depths[i] = values[rest % 3];
        rest /= 3;
      }
    }
    const Cloud::Ptr input = depthCloud (3, 3, depths);
    const Cloud expected = pclMedian (input, 3, 5.f);
    const Cloud actual = agexMedian (input, 3, 5.f, false);
    ASSERT_EQ (actual.size (), 9u);
    ASSERT_EQ (bits (actual[4].z), bits (expected[4].z)) << "pattern " << code;
    moved += expected[4].z != depths[4];
    ++patterns;
  }
  EXPECT_EQ (patterns, 13122);
  EXPECT_GT (moved, 1000);
}

TEST (DepthMedianFilter, SignedZerosComeBackAsPclReturnsThem)
{
  // +0 and -0 compare equal: the filter must pick the very zero PCL's nth_element picks.
  std::mt19937 rng (8);
  const float values[4] = {nanf_ (), 0.f, -0.f, 1.f};
  int negative = 0;
  for (int trial = 0; trial < 300; ++trial)
  {
    std::vector<float> depths (25);
    for (auto &z : depths)
      z = values[rng () % 4];
    const Cloud::Ptr input = depthCloud (5, 5, depths);
    for (int window : {3, 5})
    {
      const Cloud expected = pclMedian (input, window, 5.f);
      expectBitwiseEqual (expected, agexMedian (input, window, 5.f, false), "trial " + std::to_string (trial));
      for (const auto &p : expected)
        negative += std::signbit (p.z) && p.z == 0.f;
    }
  }
  EXPECT_GT (negative, 100);
}

TEST (DepthMedianFilter, KeepOnViewingRayScalesXAndYWithZ)
{
  const Cloud::Ptr input = randomFrame (23, 17, 4);
  for (int window : {3, 5})
    for (float max_movement : kMaxMovements)
    {
      Median median;
      EXPECT_TRUE (median.getKeepOnViewingRay ());  // the default
      median.setInputCloud (input);
      median.setWindowSize (window);
      median.setMaxAllowedMovement (max_movement);
      Cloud out;
      median.filter (out);

      // z as pcl::MedianFilter; x and y scaled by new z / old z (bit for bit what the
      // depth pipeline did after pcl::MedianFilter before this class existed).
      Cloud expected = pclMedian (input, window, max_movement);
      int moved = 0;
      for (std::size_t i = 0; i < expected.size (); ++i)
      {
        const float z0 = (*input)[i].z, z1 = expected[i].z;
        if (isFinite ((*input)[i]) && z1 != z0)
        {
          expected[i].x *= z1 / z0;
          expected[i].y *= z1 / z0;
          ++moved;
          // Still on its pixel's ray.
          EXPECT_NEAR (out[i].x / out[i].z, (*input)[i].x / z0, 1e-6f);
          EXPECT_NEAR (out[i].y / out[i].z, (*input)[i].y / z0, 1e-6f);
        }
      }
      EXPECT_GT (moved, 20);
      expectBitwiseEqual (expected, out, "window " + std::to_string (window));
    }
}

TEST (DepthMedianFilter, IndicesLimitWhatIsFilteredNotTheNeighbours)
{
  const Cloud::Ptr input = randomFrame (23, 17, 5);
  pcl::IndicesPtr some (new pcl::Indices);
  for (int i = 0; i < static_cast<int> (input->size ()); i += 3)
    some->push_back (i);
  Median median;
  median.setInputCloud (input);
  median.setIndices (some);
  median.setWindowSize (3);
  median.setMaxAllowedMovement (0.05f);
  Cloud out;
  median.filter (out);
  const Cloud all = agexMedian (input, 3, 0.05f, true);
  ASSERT_EQ (out.size (), input->size ());
  int changed = 0;
  for (std::size_t i = 0; i < input->size (); ++i)
  {
    const pcl::PointXYZ &expected = i % 3 == 0 ? all[i] : (*input)[i];
    EXPECT_EQ (bits (out[i].z), bits (expected.z)) << i;
    EXPECT_EQ (bits (out[i].x), bits (expected.x)) << i;
    changed += i % 3 == 0 && out[i].z != (*input)[i].z;
  }
  EXPECT_GT (changed, 10);
}

TEST (DepthMedianFilter, FiltersInPlaceAndKeepsOtherFields)
{
  pcl::PointCloud<pcl::PointXYZI>::Ptr cloud (new pcl::PointCloud<pcl::PointXYZI> (3, 3));
  for (std::size_t i = 0; i < cloud->size (); ++i)
  {
    (*cloud)[i].x = 0.1f * static_cast<float> (i);
    (*cloud)[i].y = 0.f;
    (*cloud)[i].z = i == 4 ? 3.f : 2.f;  // a spike in the middle
    (*cloud)[i].intensity = static_cast<float> (i);
  }
  agex::DepthMedianFilter<pcl::PointXYZI> median;
  median.setInputCloud (cloud);
  median.setWindowSize (3);
  median.filter (*cloud);
  ASSERT_EQ (cloud->size (), 9u);
  ASSERT_EQ (cloud->height, 3u);
  for (std::size_t i = 0; i < cloud->size (); ++i)
  {
    EXPECT_EQ ((*cloud)[i].z, 2.f) << i;
    EXPECT_EQ ((*cloud)[i].intensity, static_cast<float> (i));
  }
  EXPECT_FLOAT_EQ ((*cloud)[4].x, 0.4f * 2.f / 3.f);  // pulled back along its ray
}

TEST (DepthMedianFilter, MaxMovementZeroLeavesDepthsAsTheyAre)
{
  const Cloud::Ptr input = randomFrame (23, 17, 6);
  expectBitwiseEqual (*input, agexMedian (input, 3, 0.f, true), "max movement 0");
}

TEST (DepthMedianFilter, AllNaNCloudStaysAsItIs)
{
  const Cloud::Ptr input = nanCloud (11, 7);
  expectBitwiseEqual (*input, agexMedian (input, 3, 0.05f, true), "window 3");
  expectBitwiseEqual (*input, agexMedian (input, 5, 0.05f, true), "window 5");
}

TEST (DepthMedianFilter, MisuseReportsAnErrorAndGivesAnEmptyCloud)
{
  QuietPcl quiet;
  // Unorganized (height 1, PCL's definition; a 1x1 frame is one too, and PCL's
  // MedianFilter refuses it as well), window < 1, a negative or NaN max movement.
  Cloud::Ptr row (new Cloud (10, 1, pcl::PointXYZ (0.f, 0.f, 2.f)));
  Cloud::Ptr single (new Cloud (1, 1, pcl::PointXYZ (0.f, 0.f, 2.f)));
  Cloud::Ptr frame = randomFrame (5, 4, 7);
  struct Case
  {
    Cloud::Ptr input;
    int window;
    float max_movement;
  };
  for (const Case &c : {Case{row, 3, 0.05f}, Case{single, 3, 0.05f}, Case{frame, 0, 0.05f}, Case{frame, -3, 0.05f},
                        Case{frame, 3, -0.01f}, Case{frame, 3, nanf_ ()}})
  {
    Cloud out (4, 4, pcl::PointXYZ (1.f, 1.f, 1.f));
    Median median;
    median.setInputCloud (c.input);
    median.setWindowSize (c.window);
    median.setMaxAllowedMovement (c.max_movement);
    median.filter (out);
    EXPECT_TRUE (out.empty ()) << c.input->width << "x" << c.input->height << " window " << c.window;
    EXPECT_EQ (out.width, 0u);
  }
}
}  // namespace

namespace
{
TEST (DepthMedianFilter, FilterInPlaceIsFilterWithoutTheCopy)
{
  // One filter object for several frames and index sets, as a pipeline holds it: each
  // in-place run gives filter ()'s cloud, whatever the runs before it read.
  Median median;
  median.setWindowSize (3);
  median.setMaxAllowedMovement (0.05f);
  for (unsigned seed = 20; seed < 26; ++seed)
  {
    const int width = 17 + static_cast<int> (seed % 3) * 11, height = 13 + static_cast<int> (seed % 2) * 9;
    const Cloud::Ptr input = randomFrame (width, height, seed);
    pcl::IndicesPtr some (new pcl::Indices);
    for (int i = static_cast<int> (seed) % 4; i < static_cast<int> (input->size ()); i += 1 + static_cast<int> (seed) % 3)
      some->push_back (i);
    Median fresh;
    fresh.setInputCloud (input);
    fresh.setIndices (some);
    fresh.setWindowSize (3);
    fresh.setMaxAllowedMovement (0.05f);
    Cloud expected;
    fresh.filter (expected);

    Cloud::Ptr cloud (new Cloud (*input));
    median.setInputCloud (cloud);
    median.setIndices (some);
    ASSERT_TRUE (median.filterInPlace (*cloud));
    expectBitwiseEqual (expected, *cloud, "seed " + std::to_string (seed));
  }
}

TEST (DepthMedianFilter, FilterInPlaceRefusesAnotherCloud)
{
  QuietPcl quiet;
  const Cloud::Ptr input = randomFrame (9, 7, 30);
  Cloud other (*input);
  Median median;
  median.setInputCloud (input);
  median.setWindowSize (3);
  EXPECT_FALSE (median.filterInPlace (other));
  expectBitwiseEqual (*input, other, "the other cloud");
  Cloud::Ptr row (new Cloud (10, 1, pcl::PointXYZ (0.f, 0.f, 2.f)));
  median.setInputCloud (row);
  EXPECT_FALSE (median.filterInPlace (*row));  // unorganized
}
}  // namespace

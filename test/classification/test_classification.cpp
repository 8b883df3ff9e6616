// agex::FragmentDictionary and agex::PatchClassifier: fragment features on hand-built
// patches and against a naive implementation, dictionary determinism, a small training
// run on synthetic classes, model save/load round trips, damaged models, bad input.

#include <agex/classification/fragment_dictionary.h>
#include <agex/classification/patch_classifier.h>

#include "test_support.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace
{
using agex::DepthPatch;
using agex::FragmentDictionary;
using agex::FragmentDictionaryParams;
using agex::ModelError;
using agex::PatchClassifier;
using agex::PatchClassifierParams;
using agex_test::TempDir;

constexpr float kClamp = 0.3f;
/** Features are correlations of 16-bit fixed-point values: this close to the real-valued
  * definition (exact copies come out within 1e-6 of +-1, flat windows exactly 0). */
constexpr double kFixedPointTolerance = 2e-4;

DepthPatch
flatPatch (int n, float value = kClamp, float pitch = 0.6f / 41.f)
{
  DepthPatch p;
  p.size = n;
  p.metres_per_cell = pitch;
  for (int i = 0; i < n * n; ++i)
    p.patch[i] = value;
  return p;
}

DepthPatch
noisePatch (int n, std::mt19937 &rng, float amplitude = 0.1f)
{
  std::uniform_real_distribution<float> u (-amplitude, amplitude);
  DepthPatch p = flatPatch (n, 0.f);
  for (int i = 0; i < n * n; ++i)
    p.patch[i] = u (rng);
  return p;
}

/** Writes a fragment's values, scaled and offset, into patch at (x, y). */
void
paste (DepthPatch &patch, const agex::Fragment &f, int x, int y, float scale, float offset)
{
  for (int r = 0; r < f.size; ++r)
    for (int c = 0; c < f.size; ++c)
      patch.at (y + r, x + c) = offset + scale * f.values[r * f.size + c];
}

/** Builds a one-fragment dictionary cut from source (size s, given window radius). */
FragmentDictionary
oneFragment (const DepthPatch &source, int s, int window_radius, std::uint64_t seed = 7)
{
  FragmentDictionaryParams params;
  params.fragments_per_class = 1;
  params.min_size = params.max_size = s;
  params.window_radius = window_radius;
  params.seed = seed;
  FragmentDictionary dict;
  dict.build ({{&source}}, params);
  return dict;
}

/** The definition, in double: max over the clipped window of the Pearson correlation. */
double
naiveFeature (const DepthPatch &patch, const agex::Fragment &f)
{
  const int n = patch.size, s = f.size, w = f.window_radius;
  double best = -2.0;
  bool any = false;
  for (int py = std::max (0, f.y - w); py <= std::min (n - s, f.y + w); ++py)
    for (int px = std::max (0, f.x - w); px <= std::min (n - s, f.x + w); ++px)
    {
      double mp = 0.0, mf = 0.0;
      for (int r = 0; r < s; ++r)
        for (int c = 0; c < s; ++c)
        {
          mp += patch.at (py + r, px + c);
          mf += f.values[r * s + c];
        }
      mp /= s * s;
      mf /= s * s;
      double num = 0.0, vp = 0.0, vf = 0.0;
      for (int r = 0; r < s; ++r)
        for (int c = 0; c < s; ++c)
        {
          const double a = patch.at (py + r, px + c) - mp, b = f.values[r * s + c] - mf;
          num += a * b;
          vp += a * a;
          vf += b * b;
        }
      const double ncc = vp > 1e-12 && vf > 0 ? num / std::sqrt (vp * vf) : 0.0;
      best = std::max (best, ncc);
      any = true;
    }
  return any ? best : 0.0;
}

// ---------------------------------------------------------------------------------------
// Fragment features

TEST (FragmentFeatures, ExactCopyShiftedInsideTheWindowCorrelatesOne)
{
  std::mt19937 rng (11);
  const DepthPatch source = noisePatch (41, rng);
  const FragmentDictionary dict = oneFragment (source, 7, 3);
  ASSERT_EQ (dict.size (), 1u);
  const agex::Fragment &f = dict.fragments ()[0];
  EXPECT_EQ (f.size, 7);
  EXPECT_EQ (f.window_radius, 3);

  // The source itself: the fragment at its origin.
  float feature = 0.f;
  dict.computeFeatures (source, &feature);
  EXPECT_NEAR (feature, 1.f, 1e-5f);

  // A copy (scaled, offset) at every shift inside the window, on a noisy patch.
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx)
    {
      const int x = f.x + dx, y = f.y + dy;
      if (x < 0 || y < 0 || x + f.size > 41 || y + f.size > 41)
        continue;
      std::mt19937 noise (100 + dy * 7 + dx);
      DepthPatch patch = noisePatch (41, noise, 0.05f);
      paste (patch, f, x, y, 0.07f, -0.02f);
      dict.computeFeatures (patch, &feature);
      EXPECT_NEAR (feature, 1.f, 1e-5f) << "shift " << dx << "," << dy;
    }
}

TEST (FragmentFeatures, CopyOutsideTheWindowScoresLower)
{
  std::mt19937 rng (12);
  const DepthPatch source = noisePatch (41, rng);
  // Force a fragment away from the borders: redraw seeds until it is.
  FragmentDictionary dict;
  for (std::uint64_t seed = 1;; ++seed)
  {
    dict = oneFragment (source, 7, 2, seed);
    const agex::Fragment &f = dict.fragments ()[0];
    if (f.x >= 6 && f.y >= 6 && f.x + f.size + 6 <= 41 && f.y + f.size + 6 <= 41)
      break;
    ASSERT_LT (seed, 1000u);
  }
  const agex::Fragment &f = dict.fragments ()[0];
  std::mt19937 noise (5);
  DepthPatch patch = noisePatch (41, noise, 0.05f);
  paste (patch, f, f.x + 5, f.y - 5, 0.07f, 0.f);  // 5 cells away, window radius 2
  float outside = 0.f;
  dict.computeFeatures (patch, &outside);
  EXPECT_LT (outside, 0.9f);
  EXPECT_NEAR (outside, naiveFeature (patch, f), kFixedPointTolerance);

  paste (patch, f, f.x + 2, f.y - 2, 0.07f, 0.f);  // on the window's corner
  float inside = 0.f;
  dict.computeFeatures (patch, &inside);
  EXPECT_NEAR (inside, 1.f, 1e-5f);
  EXPECT_GT (inside, outside);
}

TEST (FragmentFeatures, NegatedCopyCorrelatesMinusOne)
{
  std::mt19937 rng (13);
  const DepthPatch source = noisePatch (41, rng);
  const FragmentDictionary dict = oneFragment (source, 9, 0);  // window: the origin only
  const agex::Fragment &f = dict.fragments ()[0];
  DepthPatch patch = flatPatch (41, kClamp);
  paste (patch, f, f.x, f.y, -0.05f, 0.1f);
  float feature = 0.f;
  dict.computeFeatures (patch, &feature);
  EXPECT_NEAR (feature, -1.f, 1e-5f);
  EXPECT_GE (feature, -1.f);  // clamped to [-1, 1]

  // With a window, the best position wins: on an otherwise flat patch every other
  // position overlaps the copy partly, so the maximum is above -1 but below 1.
  const FragmentDictionary windowed = oneFragment (source, 9, 2);
  const agex::Fragment &g = windowed.fragments ()[0];
  DepthPatch patch2 = flatPatch (41, kClamp);
  paste (patch2, g, g.x, g.y, -0.05f, 0.1f);
  windowed.computeFeatures (patch2, &feature);
  EXPECT_GT (feature, -1.f);
  EXPECT_LT (feature, 1.f);
  EXPECT_NEAR (feature, naiveFeature (patch2, g), kFixedPointTolerance);
}

TEST (FragmentFeatures, FlatPatchCorrelatesZero)
{
  std::mt19937 rng (14);
  std::vector<DepthPatch> sources;
  for (int i = 0; i < 4; ++i)
    sources.push_back (noisePatch (41, rng));
  FragmentDictionaryParams params;
  params.fragments_per_class = 30;
  FragmentDictionary dict;
  dict.build ({{&sources[0], &sources[1]}, {&sources[2], &sources[3]}}, params);
  ASSERT_EQ (dict.size (), 60u);
  std::vector<float> features (dict.size (), 5.f);
  for (float value : {kClamp, 0.f, -0.123f, -kClamp})
  {
    dict.computeFeatures (flatPatch (41, value), features.data ());
    for (float v : features)
      EXPECT_EQ (v, 0.f) << "flat value " << value;
  }
  // Flat where the fragments look, relief elsewhere: still 0 for a fragment whose whole
  // window is flat.
  DepthPatch half = flatPatch (41, kClamp);
  for (int r = 0; r < 41; ++r)
    for (int c = 0; c < 41; ++c)
      if (r >= 38)
        half.at (r, c) = static_cast<float> (r * c % 7) * 0.01f;
  dict.computeFeatures (half, features.data ());
  for (std::size_t i = 0; i < dict.size (); ++i)
  {
    const agex::Fragment &f = dict.fragments ()[i];
    if (std::min (41 - f.size, f.y + f.window_radius) + f.size <= 38)
    {
      EXPECT_EQ (features[i], 0.f) << "fragment " << i;
    }
  }
}

TEST (FragmentFeatures, MatchTheNaiveDefinitionOnRandomPatches)
{
  std::mt19937 rng (15);
  for (int n : {41, 21, 9, 5})
  {
    std::vector<DepthPatch> sources;
    for (int i = 0; i < 6; ++i)
      sources.push_back (noisePatch (n, rng));
    FragmentDictionaryParams params;
    params.fragments_per_class = 25;
    params.min_size = 3;
    params.max_size = 15;  // clipped to n
    params.window_radius = 5;
    FragmentDictionary dict;
    dict.build ({{&sources[0], &sources[1]}, {&sources[2]}, {&sources[3], &sources[4], &sources[5]}}, params);
    ASSERT_EQ (dict.patchSize (), n);
    std::vector<float> features (dict.size ());
    for (int trial = 0; trial < 5; ++trial)
    {
      DepthPatch patch = noisePatch (n, rng, 0.2f);
      // Some background, as real patches have.
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c)
          if ((r + 2 * c + trial) % 5 == 0)
            patch.at (r, c) = kClamp;
      dict.computeFeatures (patch, features.data ());
      for (std::size_t i = 0; i < dict.size (); ++i)
      {
        const agex::Fragment &f = dict.fragments ()[i];
        ASSERT_LE (f.size, n);
        ASSERT_LE (f.x + f.size, n);
        ASSERT_LE (f.y + f.size, n);
        EXPECT_NEAR (features[i], naiveFeature (patch, f), kFixedPointTolerance) << "n " << n << " fragment " << i;
        EXPECT_GE (features[i], -1.f);
        EXPECT_LE (features[i], 1.f);
      }
    }
  }
}

TEST (FragmentFeatures, AllKernelsGiveTheSameBits)
{
  const std::vector<std::string> kernels = FragmentDictionary::availableKernels ();
  ASSERT_FALSE (kernels.empty ());
  EXPECT_EQ (kernels.back (), "generic");
  EXPECT_EQ (FragmentDictionary::kernelName (), kernels.front ());
  std::cout << "[ info ] feature kernels:";
  for (const std::string &k : kernels)
    std::cout << " " << k;
  std::cout << std::endl;
  EXPECT_FALSE (FragmentDictionary::selectKernel ("no-such-kernel"));
  EXPECT_EQ (FragmentDictionary::kernelName (), kernels.front ());

  std::mt19937 rng (18);
  std::vector<DepthPatch> sources;
  for (int i = 0; i < 3; ++i)
    sources.push_back (noisePatch (41, rng));
  for (int radius : {0, 3, 4, 9})
  {
    FragmentDictionaryParams params;
    params.window_radius = radius;
    params.min_size = 1;
    params.max_size = 20;
    FragmentDictionary dict;
    dict.build ({{&sources[0]}, {&sources[1]}, {&sources[2]}}, params);
    std::vector<float> reference (dict.size ()), other (dict.size ());
    for (int trial = 0; trial < 6; ++trial)
    {
      DepthPatch patch = noisePatch (41, rng, 0.2f);
      for (int r = 0; r < 41; ++r)
        for (int c = 0; c < 41; ++c)
          if ((r * 3 + c + trial) % 7 < 2)
            patch.at (r, c) = kClamp;
      ASSERT_TRUE (FragmentDictionary::selectKernel ("generic"));
      dict.computeFeatures (patch, reference.data ());
      for (std::size_t i = 0; i < dict.size (); ++i)
        EXPECT_NEAR (reference[i], naiveFeature (patch, dict.fragments ()[i]), kFixedPointTolerance) << "fragment " << i;
      for (const std::string &k : kernels)
      {
        ASSERT_TRUE (FragmentDictionary::selectKernel (k));
        EXPECT_EQ (FragmentDictionary::kernelName (), k);
        dict.computeFeatures (patch, other.data ());
        for (std::size_t i = 0; i < dict.size (); ++i)
          ASSERT_EQ (agex_test::bits (other[i]), agex_test::bits (reference[i]))
            << k << ": fragment " << i << " radius " << radius;
      }
    }
  }
  ASSERT_TRUE (FragmentDictionary::selectKernel (""));
  EXPECT_EQ (FragmentDictionary::kernelName (), kernels.front ());
}

TEST (FragmentFeatures, GoldenValuesOnEveryMachine)
{
  // Fixed input (a private generator, no <random> distributions), fixed dictionary: the
  // fragments and features must hash to these values with every kernel, compiler and
  // processor, or saved models would classify differently elsewhere.
  std::uint64_t state = 12345;
  const auto next = [&state] () {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<float> ((state >> 40) & 0xffff) / 65536.f * 0.2f - 0.1f;
  };
  std::vector<DepthPatch> patches (20);
  for (DepthPatch &p : patches)
  {
    p.size = 41;
    for (int i = 0; i < 41 * 41; ++i)
      p.patch[i] = i % 13 < 3 ? kClamp : next ();
  }
  FragmentDictionary dict;
  dict.build ({{&patches[0], &patches[1]}, {&patches[2]}, {&patches[3]}}, FragmentDictionaryParams{});
  const auto fnv = [] (std::uint64_t h, float v) { return (h ^ agex_test::bits (v)) * 1099511628211ULL; };
  std::uint64_t fragments = 1469598103934665603ULL;
  for (const agex::Fragment &f : dict.fragments ())
    for (float v : f.values)
      fragments = fnv (fragments, v);
  EXPECT_EQ (fragments, 0x2cb1512dfa3d9015ULL);
  for (const std::string &k : FragmentDictionary::availableKernels ())
  {
    ASSERT_TRUE (FragmentDictionary::selectKernel (k));
    std::uint64_t features = 1469598103934665603ULL;
    std::vector<float> f (dict.size ());
    for (const DepthPatch &p : patches)
    {
      dict.computeFeatures (p, f.data ());
      for (float v : f)
        features = fnv (features, v);
    }
    EXPECT_EQ (features, 0x514b6713d3eaad31ULL) << k;
  }
  FragmentDictionary::selectKernel ("");
}

TEST (FragmentFeatures, SubsetTouchesOnlyTheListedFeatures)
{
  std::mt19937 rng (16);
  const DepthPatch a = noisePatch (41, rng), b = noisePatch (41, rng);
  FragmentDictionary dict;
  dict.build ({{&a}, {&b}}, FragmentDictionaryParams{});
  std::vector<float> all (dict.size ());
  const DepthPatch patch = noisePatch (41, rng);
  dict.computeFeatures (patch, all.data ());
  const std::vector<int> which{3, 17, 80, 159};
  std::vector<float> some (dict.size (), 42.f);
  dict.computeFeatures (patch, which, some.data ());
  for (std::size_t i = 0; i < dict.size (); ++i)
  {
    if (std::find (which.begin (), which.end (), static_cast<int> (i)) != which.end ())
      EXPECT_EQ (agex_test::bits (some[i]), agex_test::bits (all[i])) << i;
    else
      EXPECT_EQ (some[i], 42.f) << i;
  }
  EXPECT_THROW (dict.computeFeatures (patch, std::vector<int>{160}, some.data ()), std::invalid_argument);
  EXPECT_THROW (dict.computeFeatures (flatPatch (21), all.data ()), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------
// Dictionary

TEST (FragmentDictionary, SameSeedSameFragmentsOtherSeedOthers)
{
  std::mt19937 rng (17);
  std::vector<DepthPatch> patches;
  for (int i = 0; i < 9; ++i)
    patches.push_back (noisePatch (41, rng));
  const std::vector<std::vector<const DepthPatch *>> positives{
    {&patches[0], &patches[1], &patches[2]}, {&patches[3], &patches[4]}, {&patches[5], &patches[6], &patches[7], &patches[8]}};
  FragmentDictionaryParams params;
  FragmentDictionary a, b, c;
  a.build (positives, params);
  b.build (positives, params);
  params.seed = 2;
  c.build (positives, params);
  ASSERT_EQ (a.size (), 240u);
  ASSERT_EQ (b.size (), a.size ());
  ASSERT_EQ (c.size (), a.size ());
  int differ = 0;
  for (std::size_t i = 0; i < a.size (); ++i)
  {
    const agex::Fragment &fa = a.fragments ()[i], &fb = b.fragments ()[i], &fc = c.fragments ()[i];
    EXPECT_EQ (fa.cls, static_cast<int> (i / 80));
    EXPECT_EQ (fa.cls, fb.cls);
    EXPECT_EQ (fa.x, fb.x);
    EXPECT_EQ (fa.y, fb.y);
    EXPECT_EQ (fa.size, fb.size);
    EXPECT_GE (fa.size, 5);
    EXPECT_LE (fa.size, 13);
    ASSERT_EQ (fa.values.size (), static_cast<std::size_t> (fa.size * fa.size));
    for (std::size_t k = 0; k < fa.values.size (); ++k)
      ASSERT_EQ (agex_test::bits (fa.values[k]), agex_test::bits (fb.values[k]));
    // zero-mean, unit-norm
    double sum = 0.0, sq = 0.0;
    for (float v : fa.values)
    {
      sum += v;
      sq += static_cast<double> (v) * v;
    }
    EXPECT_NEAR (sum, 0.0, 1e-5);
    EXPECT_NEAR (sq, 1.0, 1e-5);
    differ += fa.x != fc.x || fa.y != fc.y || fa.size != fc.size;
  }
  EXPECT_GT (differ, 200);
}

TEST (FragmentDictionary, FlatPositivesGiveZeroFragmentsAndBadInputThrows)
{
  const DepthPatch flat = flatPatch (41);
  FragmentDictionaryParams params;
  params.fragments_per_class = 3;
  FragmentDictionary dict;
  dict.build ({{&flat}}, params);
  ASSERT_EQ (dict.size (), 3u);
  for (const agex::Fragment &f : dict.fragments ())
    for (float v : f.values)
      EXPECT_EQ (v, 0.f);

  const DepthPatch small = flatPatch (21);
  EXPECT_THROW (dict.build ({}, params), std::invalid_argument);
  EXPECT_THROW (dict.build ({{&flat}, {}}, params), std::invalid_argument);
  EXPECT_THROW (dict.build ({{&flat, nullptr}}, params), std::invalid_argument);
  EXPECT_THROW (dict.build ({{&flat}, {&small}}, params), std::invalid_argument);
  FragmentDictionaryParams bad = params;
  bad.min_size = 0;
  EXPECT_THROW (dict.build ({{&flat}}, bad), std::invalid_argument);
  bad = params;
  bad.max_size = 4;
  EXPECT_THROW (dict.build ({{&flat}}, bad), std::invalid_argument);
  bad = params;
  bad.window_radius = -1;
  EXPECT_THROW (dict.build ({{&flat}}, bad), std::invalid_argument);
  EXPECT_EQ (dict.size (), 3u);  // unchanged by the failed builds
}

// ---------------------------------------------------------------------------------------
// Synthetic classes: 0 = a vertical limb coming down to the centre, 1 = a round blob,
// -1 = background (edges, horizontal bars, slopes, noise). Depths relative to the centre,
// background +clamp, 41 x 41 cells.

DepthPatch
syntheticPatch (int label, std::mt19937 &rng)
{
  const int n = 41, c = n / 2;
  std::uniform_int_distribution<int> jitter (-3, 3);
  std::uniform_real_distribution<float> u (0.f, 1.f);
  std::normal_distribution<float> noise (0.f, 0.005f);
  DepthPatch p = flatPatch (n, kClamp);
  const auto set = [&] (int r, int col, float v) {
    if (r >= 0 && r < n && col >= 0 && col < n)
      p.at (r, col) = std::clamp (v + noise (rng), -kClamp, kClamp);
  };
  // A limb coming down from the top edge to (cx, tip), leaning, 2 half + 1 cells wide.
  const auto limb = [&] (int cx, int tip, int half) {
    const float lean = (u (rng) - 0.5f) * 0.4f, slope = (u (rng) - 0.5f) * 0.006f;
    for (int r = 0; r <= std::min (tip, n - 1); ++r)
    {
      const int x = cx + static_cast<int> (std::lround (lean * (tip - r)));
      for (int col = x - half; col <= x + half; ++col)
        set (r, col, slope * (tip - r) + 0.003f * (col - x) * (col - x));
    }
  };
  const auto blob = [&] (int cx, int cy, float radius) {
    for (int r = 0; r < n; ++r)
      for (int col = 0; col < n; ++col)
      {
        const float d2 = static_cast<float> ((r - cy) * (r - cy) + (col - cx) * (col - cx));
        if (d2 <= radius * radius)
          set (r, col, -0.04f * (1.f - d2 / (radius * radius)));
      }
  };
  const auto offCentre = [&] () {  // 9..14 cells from the centre, either side
    const int d = 9 + static_cast<int> (u (rng) * 6);
    return u (rng) < 0.5f ? c - d : c + d;
  };
  if (label == 0)  // a limb tip at the centre
    limb (c + jitter (rng), c + jitter (rng), 1 + static_cast<int> (u (rng) * 3));
  else if (label == 1)  // a head: a round blob at the centre, sometimes with a neck
  {
    const int cx = c + jitter (rng), cy = c + jitter (rng);
    const float radius = 5.f + u (rng) * 3.f;
    if (u (rng) < 0.5f)
      limb (cx, cy, 1);
    blob (cx, cy, radius);
  }
  else
  {
    const int kind = static_cast<int> (u (rng) * 7);
    if (kind == 0)  // a surface edge: half the patch is a slanted plane
    {
      const float a = u (rng) * 6.283f, s = (u (rng) - 0.5f) * 0.02f;
      for (int r = 0; r < n; ++r)
        for (int col = 0; col < n; ++col)
          if (std::cos (a) * (col - c) + std::sin (a) * (r - c) >= 0)
            set (r, col, s * (r - c));
    }
    else if (kind == 1)  // a horizontal bar through the centre
    {
      const int cy = c + jitter (rng), half = 1 + static_cast<int> (u (rng) * 3);
      for (int r = cy - half; r <= cy + half; ++r)
        for (int col = 0; col < n; ++col)
          set (r, col, 0.f);
    }
    else if (kind == 2)  // a slope everywhere
    {
      const float sx = (u (rng) - 0.5f) * 0.02f, sy = (u (rng) - 0.5f) * 0.02f;
      for (int r = 0; r < n; ++r)
        for (int col = 0; col < n; ++col)
          set (r, col, sx * (col - c) + sy * (r - c));
    }
    else if (kind == 3)  // clutter
    {
      for (int r = 0; r < n; ++r)
        for (int col = 0; col < n; ++col)
          set (r, col, (u (rng) - 0.5f) * 0.4f);
    }
    else if (kind == 4)  // a limb passing through, not ending here
      limb (c + jitter (rng), n - 1, 1 + static_cast<int> (u (rng) * 3));
    else if (kind == 5)  // a limb tip away from the centre
      limb (offCentre (), c + jitter (rng), 1 + static_cast<int> (u (rng) * 3));
    else  // a blob away from the centre
      blob (offCentre (), offCentre (), 5.f + u (rng) * 3.f);
  }
  return p;
}

struct SyntheticSet
{
  std::vector<DepthPatch> patches;
  std::vector<int> labels;
};

SyntheticSet
syntheticSet (int per_class, int background, unsigned seed)
{
  std::mt19937 rng (seed);
  SyntheticSet set;
  for (int i = 0; i < 2 * per_class + background; ++i)
  {
    const int label = i < per_class ? 0 : i < 2 * per_class ? 1 : -1;
    set.patches.push_back (syntheticPatch (label, rng));
    set.labels.push_back (label);
  }
  return set;
}

PatchClassifierParams
smallParams ()
{
  PatchClassifierParams params;
  params.dictionary.fragments_per_class = 40;
  params.weak_count = 60;
  return params;
}

/** One trained classifier shared by the tests below (training once keeps them fast). */
const PatchClassifier &
trainedClassifier ()
{
  static const PatchClassifier classifier = [] {
    const SyntheticSet train = syntheticSet (150, 300, 1);
    PatchClassifier c;
    c.train (train.patches, train.labels, 2, smallParams ());
    return c;
  }();
  return classifier;
}

TEST (PatchClassifier, SeparatesSyntheticClasses)
{
  const SyntheticSet train = syntheticSet (150, 300, 1);
  std::vector<std::pair<int, int>> progress;
  PatchClassifier classifier;
  EXPECT_FALSE (classifier.trained ());
  const auto t0 = std::chrono::steady_clock::now ();
  classifier.train (train.patches, train.labels, 2, smallParams (),
                    [&] (int done, int total) { progress.emplace_back (done, total); });
  const double train_s = std::chrono::duration<double> (std::chrono::steady_clock::now () - t0).count ();
  ASSERT_TRUE (classifier.trained ());
  EXPECT_EQ (classifier.classes (), 2);
  EXPECT_EQ (progress, (std::vector<std::pair<int, int>>{{1, 2}, {2, 2}}));
  EXPECT_EQ (classifier.dictionary ().size (), 80u);
  EXPECT_FALSE (classifier.usedFragments ().empty ());
  EXPECT_LE (classifier.usedFragments ().size (), 80u);
  EXPECT_EQ (classifier.patchGeometry ().size, 41);
  EXPECT_NEAR (classifier.patchGeometry ().extent, 0.6f, 1e-6f);
  EXPECT_EQ (classifier.patchGeometry ().clamp, kClamp);

  const SyntheticSet test = syntheticSet (100, 200, 2);
  int correct = 0;
  double conf_pos[2] = {0, 0}, conf_neg[2] = {0, 0};
  int n_pos[2] = {0, 0}, n_neg[2] = {0, 0};
  float margins[2], confidences[2];
  for (std::size_t i = 0; i < test.patches.size (); ++i)
  {
    classifier.classify (test.patches[i], margins, confidences);
    const int best = margins[0] >= margins[1] ? 0 : 1;
    const int predicted = margins[best] > 0.f ? best : -1;
    correct += predicted == test.labels[i];
    for (int c = 0; c < 2; ++c)
    {
      ASSERT_GE (confidences[c], 0.f);
      ASSERT_LE (confidences[c], 1.f);
      EXPECT_NEAR (confidences[c], 1.0 / (1.0 + std::exp (-2.0 * margins[c])), 1e-6);
      if (test.labels[i] == c)
      {
        conf_pos[c] += confidences[c];
        ++n_pos[c];
      }
      else
      {
        conf_neg[c] += confidences[c];
        ++n_neg[c];
      }
    }
  }
  const double accuracy = static_cast<double> (correct) / test.patches.size ();
  EXPECT_GT (accuracy, 0.9);
  for (int c = 0; c < 2; ++c)
    EXPECT_GT (conf_pos[c] / n_pos[c], conf_neg[c] / n_neg[c] + 0.3) << "class " << c;

  // Timing is reported, not tested (speed targets live in the benchmarks).
  const int repeats = 20;
  const auto t1 = std::chrono::steady_clock::now ();
  float sink = 0.f;
  for (int k = 0; k < repeats; ++k)
    for (const DepthPatch &p : test.patches)
    {
      classifier.classify (p, margins, confidences);
      sink += margins[0];
    }
  const double per_patch_us = std::chrono::duration<double, std::micro> (std::chrono::steady_clock::now () - t1).count () /
                              (repeats * test.patches.size ());
  std::cout << "[ info ] " << train.patches.size () << " patches trained in " << train_s << " s; held-out accuracy "
            << accuracy << "; classify " << per_patch_us << " us/patch (" << classifier.usedFragments ().size ()
            << " of " << classifier.dictionary ().size () << " fragments used, 2 classes x 60 stumps)" << (sink > 1e30f ? "" : "")
            << std::endl;
}

TEST (PatchClassifier, MarginsAreWhatCvMlBoostPredicts)
{
  const PatchClassifier &classifier = trainedClassifier ();
  const SyntheticSet test = syntheticSet (20, 40, 3);
  std::vector<float> features (classifier.dictionary ().size ());
  float margins[2];
  for (const DepthPatch &p : test.patches)
  {
    classifier.dictionary ().computeFeatures (p, features.data ());
    classifier.classify (p, margins, nullptr);
    const cv::Mat row (1, static_cast<int> (features.size ()), CV_32F, features.data ());
    for (int c = 0; c < 2; ++c)
    {
      const float expected =
        classifier.boosters ()[c]->predict (row, cv::noArray (), cv::ml::StatModel::RAW_OUTPUT | cv::ml::DTrees::PREDICT_SUM);
      EXPECT_EQ (agex_test::bits (margins[c]), agex_test::bits (expected));
    }
  }
}

TEST (PatchClassifier, BadInputThrows)
{
  const SyntheticSet set = syntheticSet (5, 10, 4);
  const PatchClassifierParams params = smallParams ();
  PatchClassifier c;
  std::vector<int> labels = set.labels;
  labels.pop_back ();
  EXPECT_THROW (c.train (set.patches, labels, 2, params), std::invalid_argument);  // size mismatch
  EXPECT_THROW (c.train ({}, {}, 2, params), std::invalid_argument);
  EXPECT_THROW (c.train (set.patches, set.labels, 3, params), std::invalid_argument);  // class 2 has no positives
  EXPECT_THROW (c.train (set.patches, set.labels, 0, params), std::invalid_argument);
  labels = set.labels;
  labels[0] = 2;
  EXPECT_THROW (c.train (set.patches, labels, 2, params), std::invalid_argument);  // label out of range
  labels[0] = -2;
  EXPECT_THROW (c.train (set.patches, labels, 2, params), std::invalid_argument);
  std::vector<DepthPatch> patches = set.patches;
  patches[3] = flatPatch (21);
  EXPECT_THROW (c.train (patches, set.labels, 2, params), std::invalid_argument);  // mixed sizes
  patches = set.patches;
  patches[3].patch[5] = agex_test::nanf_ ();
  EXPECT_THROW (c.train (patches, set.labels, 2, params), std::invalid_argument);
  // One class and no background: no negatives.
  std::vector<DepthPatch> only (set.patches.begin (), set.patches.begin () + 5);
  EXPECT_THROW (c.train (only, std::vector<int> (5, 0), 1, params), std::invalid_argument);
  PatchClassifierParams bad = params;
  bad.weak_count = 0;
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad = params;
  bad.weight_trim_rate = 1.5;
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad = params;
  bad.cascade_levels = {0.2f, 0.1f};  // not increasing
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad.cascade_levels = {1.f};
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad = params;
  bad.cascade_stage_ends = {0, 4};
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad.cascade_stage_ends.assign (33, 1);
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad = params;
  bad.cascade_miss_rates = {0.6f};
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  bad.cascade_miss_rates = {0.02f, 0.01f};
  EXPECT_THROW (c.train (set.patches, set.labels, 2, bad), std::invalid_argument);
  EXPECT_FALSE (c.trained ());

  float m[2], conf[2];
  EXPECT_THROW (c.classify (set.patches[0], m, conf), std::logic_error);
  TempDir dir;
  EXPECT_THROW (c.save (dir.file ("untrained.yml"), nlohmann::json ()), std::logic_error);
  EXPECT_THROW (trainedClassifier ().classify (flatPatch (21), m, conf), std::invalid_argument);
}

TEST (SoftCascade, KeepsEveryTrainingPositiveOfItsLevelAndRejectsBackground)
{
  const SyntheticSet train = syntheticSet (150, 300, 1);
  const PatchClassifier &classifier = trainedClassifier ();  // trained on the same set
  const agex::SoftCascade &cascade = classifier.cascade ();
  ASSERT_FALSE (cascade.empty ());
  // smallParams: 60 rounds, so the stage ends below 60 remain.
  EXPECT_EQ (cascade.stage_ends, (std::vector<int>{4, 8, 16, 32}));
  EXPECT_EQ (cascade.levels, PatchClassifierParams ().cascade_levels);
  EXPECT_EQ (cascade.levelFor (0.f), -1);
  EXPECT_EQ (cascade.levelFor (0.019f), -1);
  EXPECT_EQ (cascade.levelFor (0.05f), 1);
  EXPECT_EQ (cascade.levelFor (0.5f), static_cast<int> (cascade.levels.size ()) - 1);

  float full_m[2], full_c[2], m[2], conf[2];
  for (std::size_t l = 0; l < cascade.levels.size (); ++l)
  {
    const float level = cascade.levels[l];
    int checked = 0;
    for (std::size_t i = 0; i < train.patches.size (); ++i)
    {
      const int label = train.labels[i];
      classifier.classify (train.patches[i], full_m, full_c);
      if (label < 0 || full_c[label] < level)
        continue;
      ++checked;
      ASSERT_TRUE (classifier.classifyCascade (train.patches[i], nullptr, level, m, conf))
          << "training positive " << i << " of class " << label << " (confidence " << full_c[label]
          << ") rejected at level " << level;
      for (int c = 0; c < 2; ++c)
        ASSERT_EQ (agex_test::bits (m[c]), agex_test::bits (full_m[c]));
    }
    EXPECT_GT (checked, 250) << "level " << level;
  }

  // (Miss rates: SoftCascade.MissRatesBoundTheRejectedPositivesOfEachClass.)
  // Held out: a patch the cascade keeps gets exactly classify ()'s values; background is
  // mostly rejected; held-out positives mostly kept.
  const SyntheticSet test = syntheticSet (100, 200, 2);
  int rejected_background = 0, background = 0, kept_positive = 0, positive = 0;
  for (std::size_t i = 0; i < test.patches.size (); ++i)
  {
    classifier.classify (test.patches[i], full_m, full_c);
    const bool kept = classifier.classifyCascade (test.patches[i], nullptr, 0.1f, m, conf);
    if (kept)
      for (int c = 0; c < 2; ++c)
      {
        ASSERT_EQ (agex_test::bits (m[c]), agex_test::bits (full_m[c]));
        ASSERT_EQ (agex_test::bits (conf[c]), agex_test::bits (full_c[c]));
      }
    // Off (below every level): classify () itself.
    ASSERT_TRUE (classifier.classifyCascade (test.patches[i], nullptr, 0.f, m, conf));
    ASSERT_EQ (agex_test::bits (m[0]), agex_test::bits (full_m[0]));
    if (test.labels[i] < 0)
    {
      ++background;
      rejected_background += !kept;
    }
    else
    {
      ++positive;
      kept_positive += kept;
    }
  }
  std::cout << "[ info ] cascade at 0.1: " << rejected_background << " of " << background
            << " background patches rejected, " << kept_positive << " of " << positive << " positives kept" << std::endl;
  EXPECT_GT (rejected_background, background / 2);
  EXPECT_GT (kept_positive, positive * 9 / 10);
}

TEST (SoftCascade, MissRatesBoundTheRejectedPositivesOfEachClass)
{
  const SyntheticSet train = syntheticSet (150, 300, 1);
  PatchClassifierParams params = smallParams ();
  params.cascade_miss_rates = {0.f, 0.2f, 0.4f};
  PatchClassifier classifier;
  classifier.train (train.patches, train.labels, 2, params);
  const agex::SoftCascade &cascade = classifier.cascade ();
  ASSERT_EQ (cascade.miss_rates, params.cascade_miss_rates);
  float full_m[2], full_c[2], m[2], conf[2];
  int rejected_at_04 = 0;
  for (const float level : cascade.levels)
    for (int c = 0; c < 2; ++c)
      for (const float rate : cascade.miss_rates)
      {
        int reaching = 0, rejected = 0;
        for (std::size_t i = 0; i < train.patches.size (); ++i)
        {
          if (train.labels[i] != c)
            continue;
          classifier.classify (train.patches[i], full_m, full_c);
          if (full_c[c] < level)
            continue;
          ++reaching;
          rejected += !classifier.classifyCascade (train.patches[i], nullptr, level, m, conf, rate);
        }
        SCOPED_TRACE ("class " + std::to_string (c) + ", level " + std::to_string (level) + ", miss rate " +
                      std::to_string (rate));
        EXPECT_GT (reaching, 100);
        EXPECT_LE (rejected, rate * reaching);
        if (rate == 0.4f)
          rejected_at_04 += rejected;
      }
  EXPECT_GT (rejected_at_04, 0) << "the miss rate rejected nothing";
  float unused[2];
  EXPECT_THROW (classifier.classifyCascade (train.patches[0], nullptr, 0.1f, unused, unused, -0.1f),
                std::invalid_argument);
  EXPECT_THROW (classifier.classifyCascade (train.patches[0], nullptr, 0.1f, unused, unused,
                                            std::numeric_limits<float>::quiet_NaN ()),
                std::invalid_argument);
}

TEST (SoftCascade, FittingATrainedClassifierGivesTrainsThresholds)
{
  const SyntheticSet train = syntheticSet (150, 300, 1);
  PatchClassifierParams params = smallParams ();
  params.cascade_levels.clear ();  // trained without a cascade, as models before it were
  PatchClassifier bare;
  EXPECT_THROW (bare.fitCascade (train.patches, {}, train.labels, {4}, {0.1f}, {0.f}), std::logic_error);
  bare.train (train.patches, train.labels, 2, params);
  ASSERT_TRUE (bare.cascade ().empty ());
  const PatchClassifier &with = trainedClassifier ();  // the same set, the default cascade
  const PatchClassifierParams defaults;
  bare.fitCascade (train.patches, {}, train.labels, defaults.cascade_stage_ends, defaults.cascade_levels,
                   defaults.cascade_miss_rates);
  EXPECT_EQ (bare.cascade ().stage_ends, with.cascade ().stage_ends);
  ASSERT_EQ (bare.cascade ().thresholds.size (), with.cascade ().thresholds.size ());
  for (std::size_t i = 0; i < bare.cascade ().thresholds.size (); ++i)
    ASSERT_EQ (agex_test::bits (bare.cascade ().thresholds[i]), agex_test::bits (with.cascade ().thresholds[i]));
  // Refused fits leave the cascade as it was.
  const std::vector<float> before = bare.cascade ().thresholds;
  EXPECT_THROW (bare.fitCascade (train.patches, {}, train.labels, {4}, {0.2f, 0.1f}, {0.f}), std::invalid_argument);
  std::vector<DepthPatch> small (train.patches.size (), flatPatch (21));
  EXPECT_THROW (bare.fitCascade (small, {}, train.labels, {4}, {0.1f}, {0.f}), std::invalid_argument);
  EXPECT_EQ (bare.cascade ().thresholds, before);
}

TEST (SoftCascade, NoCascadeWithoutLevelsOrStages)
{
  const SyntheticSet train = syntheticSet (40, 80, 1);
  PatchClassifierParams params = smallParams ();
  params.cascade_levels.clear ();
  PatchClassifier c;
  c.train (train.patches, train.labels, 2, params);
  EXPECT_TRUE (c.cascade ().empty ());
  params = smallParams ();
  params.cascade_stage_ends = {60, 100};  // none below the 60 rounds
  c.train (train.patches, train.labels, 2, params);
  EXPECT_TRUE (c.cascade ().empty ());
  float m[2], conf[2], full_m[2];
  for (const DepthPatch &p : train.patches)
  {
    c.classify (p, full_m, nullptr);
    ASSERT_TRUE (c.classifyCascade (p, nullptr, 0.5f, m, conf));
    ASSERT_EQ (agex_test::bits (m[1]), agex_test::bits (full_m[1]));
  }
  EXPECT_THROW (c.classifyCascade (flatPatch (21), nullptr, 0.5f, m, conf), std::invalid_argument);
}

TEST (SoftCascade, ALevelNoPositiveReachesNeverRejectsAndRoundTrips)
{
  // Five stumps cannot reach a confidence of 0.999999: no positive sets a threshold, so the
  // cascade rejects nothing at that level, and the model still saves and loads unchanged.
  const SyntheticSet train = syntheticSet (40, 80, 1);
  PatchClassifierParams params = smallParams ();
  params.weak_count = 5;
  params.cascade_stage_ends = {1, 2};
  params.cascade_levels = {0.05f, 0.999999f};
  PatchClassifier c;
  c.train (train.patches, train.labels, 2, params);
  ASSERT_FALSE (c.cascade ().empty ());
  for (std::size_t m = 0; m < c.cascade ().miss_rates.size (); ++m)
    for (std::size_t k = 0; k < 2 * 2; ++k)  // level 1: both classes, both stages
      EXPECT_EQ (c.cascade ().threshold (m, 1, k / 2, k % 2), -1e30f);
  float m[2], conf[2];
  for (const DepthPatch &p : train.patches)
    ASSERT_TRUE (c.classifyCascade (p, nullptr, 0.999999f, m, conf, 0.5f));
  TempDir dir;
  c.save (dir.file ("a.yml"), nlohmann::json ());
  const PatchClassifier loaded = PatchClassifier::load (dir.file ("a.yml"));
  EXPECT_EQ (loaded.params ().cascade_levels, params.cascade_levels);
  EXPECT_EQ (loaded.params ().cascade_stage_ends, params.cascade_stage_ends);
  EXPECT_EQ (loaded.params ().cascade_miss_rates, params.cascade_miss_rates);
  loaded.save (dir.file ("b.yml"), nlohmann::json ());
  EXPECT_EQ (agex_test::readAll (dir.file ("a.yml")), agex_test::readAll (dir.file ("b.yml")));

  // The first cascades had no miss rates: such a file reads as direct backward pruning.
  params.cascade_miss_rates = {0.f};
  c.train (train.patches, train.labels, 2, params);
  c.save (dir.file ("c.yml"), nlohmann::json ());
  const std::string text = agex_test::readAll (dir.file ("c.yml"));
  const std::size_t at = text.find ("   miss_rates: [ 0. ]\n");
  ASSERT_NE (at, std::string::npos);
  agex_test::writeAll (dir.file ("d.yml"), text.substr (0, at) + text.substr (text.find ('\n', at) + 1));
  const PatchClassifier old = PatchClassifier::load (dir.file ("d.yml"));
  EXPECT_EQ (old.cascade ().miss_rates, std::vector<float>{0.f});
  EXPECT_EQ (old.cascade ().thresholds, c.cascade ().thresholds);
}

// ---------------------------------------------------------------------------------------
// Model files

nlohmann::json
nastyMetadata ()
{
  nlohmann::json meta;
  meta["agex"] = {{"k", 20}, {"geodesic", true}, {"voxel", 0.005}};
  meta["command"] = "agex_train --data \"/tmp/a b\" --out 'model.yml' \\ # not a comment: [x] {y}";
  meta["unicode"] = "Kopf \xc3\xa9\xe2\x82\xac \xf0\x9f\x91\x8b";
  meta["padded"] = "  leading and trailing  ";
  meta["quoted"] = "\"all quoted\"";
  meta["long"] = std::string (9000, 'x') + "|end";
  meta["numbers"] = {1, 2.5, -3e-7, nullptr};
  meta["newlines"] = "line 1\nline 2\ttab";
  return meta;
}

TEST (ModelFile, RoundTripGivesIdenticalMarginsAndMetadata)
{
  const PatchClassifier &classifier = trainedClassifier ();
  TempDir dir;
  const std::string path = dir.file ("model.yml");
  const nlohmann::json meta = nastyMetadata ();
  classifier.save (path, meta);
  const PatchClassifier loaded = PatchClassifier::load (path);
  ASSERT_TRUE (loaded.trained ());
  EXPECT_EQ (loaded.classes (), 2);
  EXPECT_EQ (loaded.metadata (), meta);
  EXPECT_EQ (loaded.patchGeometry ().size, classifier.patchGeometry ().size);
  EXPECT_EQ (agex_test::bits (loaded.patchGeometry ().extent), agex_test::bits (classifier.patchGeometry ().extent));
  EXPECT_EQ (agex_test::bits (loaded.patchGeometry ().clamp), agex_test::bits (classifier.patchGeometry ().clamp));
  EXPECT_EQ (loaded.params ().weak_count, classifier.params ().weak_count);
  EXPECT_EQ (loaded.params ().dictionary.fragments_per_class, 40);
  EXPECT_EQ (loaded.params ().dictionary.seed, classifier.params ().dictionary.seed);
  EXPECT_EQ (loaded.usedFragments (), classifier.usedFragments ());
  ASSERT_FALSE (loaded.cascade ().empty ());
  EXPECT_EQ (loaded.cascade ().stage_ends, classifier.cascade ().stage_ends);
  EXPECT_EQ (loaded.cascade ().levels, classifier.cascade ().levels);
  ASSERT_EQ (loaded.cascade ().thresholds.size (), classifier.cascade ().thresholds.size ());
  for (std::size_t i = 0; i < loaded.cascade ().thresholds.size (); ++i)
    ASSERT_EQ (agex_test::bits (loaded.cascade ().thresholds[i]), agex_test::bits (classifier.cascade ().thresholds[i]));
  ASSERT_EQ (loaded.dictionary ().size (), classifier.dictionary ().size ());
  for (std::size_t i = 0; i < loaded.dictionary ().size (); ++i)
  {
    const agex::Fragment &a = classifier.dictionary ().fragments ()[i], &b = loaded.dictionary ().fragments ()[i];
    ASSERT_EQ (a.values.size (), b.values.size ());
    for (std::size_t k = 0; k < a.values.size (); ++k)
      ASSERT_EQ (agex_test::bits (a.values[k]), agex_test::bits (b.values[k]));
  }

  const SyntheticSet test = syntheticSet (100, 200, 5);
  float m1[2], c1[2], m2[2], c2[2];
  for (const DepthPatch &p : test.patches)
  {
    classifier.classify (p, m1, c1);
    loaded.classify (p, m2, c2);
    for (int c = 0; c < 2; ++c)
    {
      ASSERT_EQ (agex_test::bits (m1[c]), agex_test::bits (m2[c]));
      ASSERT_EQ (agex_test::bits (c1[c]), agex_test::bits (c2[c]));
    }
    const bool kept = classifier.classifyCascade (p, nullptr, 0.05f, m1, c1);
    ASSERT_EQ (loaded.classifyCascade (p, nullptr, 0.05f, m2, c2), kept);
    ASSERT_EQ (agex_test::bits (m1[0]), agex_test::bits (m2[0]));
  }

  // Saving the loaded model gives the same file, byte for byte.
  const std::string again = dir.file ("again.yml");
  loaded.save (again, loaded.metadata ());
  EXPECT_EQ (agex_test::readAll (again), agex_test::readAll (path));

  // A model with other patch geometry and null metadata.
  PatchClassifier copy = classifier;
  copy.setPatchGeometry ({41, 0.8f, 0.25f});
  EXPECT_THROW (copy.setPatchGeometry ({21, 0.8f, 0.25f}), std::invalid_argument);
  EXPECT_THROW (copy.setPatchGeometry ({41, 0.f, 0.25f}), std::invalid_argument);
  copy.save (path, nlohmann::json ());  // replaces the file atomically
  const PatchClassifier loaded2 = PatchClassifier::load (path);
  EXPECT_TRUE (loaded2.metadata ().is_null ());
  EXPECT_EQ (loaded2.patchGeometry ().extent, 0.8f);
  EXPECT_EQ (loaded2.patchGeometry ().clamp, 0.25f);
}

/** Expects load to throw ModelError whose message names the file (and contains what). */
void
expectModelError (const std::string &path, const std::string &what = "")
{
  try
  {
    PatchClassifier::load (path);
    ADD_FAILURE () << path << " loaded";
  }
  catch (const ModelError &e)
  {
    const std::string message = e.what ();
    EXPECT_NE (message.find (path), std::string::npos) << message;
    EXPECT_NE (message.find (what), std::string::npos) << message;
  }
  catch (const std::exception &e)
  {
    ADD_FAILURE () << path << ": not a ModelError: " << e.what ();
  }
}

std::string
replaceOnce (std::string text, const std::string &from, const std::string &to)
{
  const std::size_t at = text.find (from);
  EXPECT_NE (at, std::string::npos) << from;
  if (at != std::string::npos)
    text.replace (at, from.size (), to);
  return text;
}

TEST (ModelFile, DamagedModelsThrowModelErrorNamingTheFile)
{
  const PatchClassifier &classifier = trainedClassifier ();
  TempDir dir;
  const std::string good = dir.file ("good.yml");
  classifier.save (good, {{"note", "damage tests"}});
  const std::string text = agex_test::readAll (good);
  ASSERT_GT (text.size (), 1000u);
  ASSERT_NO_THROW (PatchClassifier::load (good));

  expectModelError (dir.file ("missing.yml"), "not found");
  expectModelError (dir.path ().string (), "directory");

  const std::string empty = dir.file ("empty.yml");
  agex_test::writeAll (empty, "");
  expectModelError (empty, "empty");

  const std::string other = dir.file ("other.yml");
  agex_test::writeAll (other, "just some text\n");
  expectModelError (other, "not an agex model");
  agex_test::writeAll (other, "%YAML:1.0\n---\nformat: something-else\nformat_version: 1\n");
  expectModelError (other, "not an agex model");
  agex_test::writeAll (other, "%YAML:1.0\n---\nrows: 3\n");
  expectModelError (other, "not an agex model");

  // Truncated anywhere.
  const std::string cut = dir.file ("cut.yml");
  for (std::size_t at : {std::size_t (1), std::size_t (10), std::size_t (30), std::size_t (100), text.size () / 8,
                         text.size () / 4, text.size () / 3, text.size () / 2, 2 * text.size () / 3,
                         3 * text.size () / 4, 7 * text.size () / 8, text.size () - 40, text.size () - 20,
                         text.size () - 5})
  {
    agex_test::writeAll (cut, text.substr (0, at));
    SCOPED_TRACE ("cut at " + std::to_string (at) + " of " + std::to_string (text.size ()));
    expectModelError (cut);
  }
  // ... and at every line break of the last part (a cut there is valid YAML).
  for (std::size_t at = text.find ('\n', text.size () - 3000); at != std::string::npos && at + 1 < text.size ();
       at = text.find ('\n', at + 1))
  {
    agex_test::writeAll (cut, text.substr (0, at + 1));
    SCOPED_TRACE ("cut at line break " + std::to_string (at));
    expectModelError (cut);
  }

  const std::string v3 = dir.file ("v3.yml");
  agex_test::writeAll (v3, replaceOnce (text, "format_version: 1", "format_version: 3"));
  expectModelError (v3, "model format version 3 is not supported (this build reads 2)");
  // Version 2 holds auxiliary features; a version-1 file that claims them is damaged.
  const std::string aux_in_v1 = dir.file ("aux_in_v1.yml");
  agex_test::writeAll (aux_in_v1, replaceOnce (text, "boosters:", "auxiliary_features:\n   - \"|x|\"\nboosters:"));
  expectModelError (aux_in_v1, "invalid auxiliary_features");

  // No dictionary.
  const std::string nodict = dir.file ("nodict.yml");
  const std::size_t d0 = text.find ("\ndictionary:"), d1 = text.find ("\nboosters:");
  ASSERT_NE (d0, std::string::npos);
  ASSERT_NE (d1, std::string::npos);
  agex_test::writeAll (nodict, text.substr (0, d0) + text.substr (d1));
  expectModelError (nodict, "dictionary");
  // A minimal YAML with the header fields only.
  agex_test::writeAll (nodict, "%YAML:1.0\n---\nformat: agex-model\nformat_version: 1\nclasses: 2\nend: agex-model\n");
  expectModelError (nodict, "damaged");

  // A fragment of the wrong size.
  const std::string wrong = dir.file ("wrong.yml");
  const int size0 = classifier.dictionary ().fragments ()[0].size;
  agex_test::writeAll (wrong, replaceOnce (text, "size:" + std::to_string (size0) + ",", "size:" + std::to_string (size0 + 1) + ","));
  expectModelError (wrong, "fragment 0");

  // A booster that uses a feature the dictionary does not have, and one that fails to load.
  const std::string badvar = dir.file ("badvar.yml");
  const std::size_t var = text.find ("{ var:", d1);
  ASSERT_NE (var, std::string::npos);
  std::string t = text;
  t.replace (var, text.find (',', var) - var, "{ var:100000");
  agex_test::writeAll (badvar, t);
  expectModelError (badvar, "booster 0");
  agex_test::writeAll (badvar, replaceOnce (text, "ntrees: 60", "ntrees: 61"));
  expectModelError (badvar, "booster 0");
  agex_test::writeAll (badvar, replaceOnce (text, "classes: 2", "classes: 3"));
  expectModelError (badvar, "boosters");

  // A damaged soft cascade (the trained one: stage ends 4, 8, 16, 32 of 60 rounds).
  const std::string casc = dir.file ("cascade.yml");
  const std::string ends = "stage_ends: [ 4, 8, 16, 32 ]";
  ASSERT_NE (text.find (ends), std::string::npos);
  for (const char *bad : {"stage_ends: [ 8, 4, 16, 32 ]", "stage_ends: [ 4, 8, 16, 60 ]",
                                 "stage_ends: [ 4, 8, 16, 32.5 ]", "stage_ends: [ 4, x, 16, 32 ]",
                                 "stage_ends: []", "stage_ends: 4"})
  {
    agex_test::writeAll (casc, replaceOnce (text, ends, bad));
    expectModelError (casc, "cascade");
  }
  std::string many = "stage_ends: [ 1";
  for (int e = 2; e <= 40; ++e)
    many += ", " + std::to_string (e);
  agex_test::writeAll (casc, replaceOnce (text, ends, many + " ]"));
  expectModelError (casc, "cascade");
  // The first value of a cascade list replaced, and the file refused.
  const auto refusedWithFirst = [&] (const std::string &list, const std::string &value) {
    const std::size_t first = text.find (list + ": [ ") + list.size () + 4;
    std::string t = text;
    t.replace (first, text.find (',', first) - first, value);
    agex_test::writeAll (casc, t);
    expectModelError (casc, "cascade");
  };
  for (const char *bad : {"1e+40", ".nan", "x"})
    refusedWithFirst ("thresholds", bad);
  refusedWithFirst ("levels", "1.5");
  refusedWithFirst ("miss_rates", "0.7");
  const std::size_t first = text.find ("thresholds: [ ") + 14;
  std::string fewer = text;
  fewer.erase (first, text.find (',', first) - first + 2);  // one threshold short
  agex_test::writeAll (casc, fewer);
  expectModelError (casc, "cascade");
  agex_test::writeAll (casc, replaceOnce (text, "cascade:\n", "cascade: 3\nold_cascade:\n"));
  expectModelError (casc, "cascade");

  // Metadata that is not JSON.
  const std::string meta = dir.file ("meta.yml");
  agex_test::writeAll (meta, replaceOnce (text, "\"|{", "\"|{{"));
  expectModelError (meta, "metadata");
}

/** The depth of the node tree cv::FileStorage built: its parser recursed this deep. */
std::size_t
treeDepth (const cv::FileNode &root)
{
  std::size_t deepest = 0;
  std::vector<std::pair<cv::FileNode, std::size_t>> stack{{root, 1}};
  while (!stack.empty ())
  {
    const auto [node, depth] = stack.back ();
    stack.pop_back ();
    deepest = std::max (deepest, depth);
    if (node.isMap () || node.isSeq ())
      for (cv::FileNodeIterator it = node.begin (); it != node.end (); ++it)
        stack.push_back ({*it, depth + 1});
  }
  return deepest;
}

std::string
repeat (const std::string &text, int times)
{
  std::string out;
  for (int i = 0; i < times; ++i)
    out += text;
  return out;
}

TEST (ModelFile, DeepNestingIsRefusedBeforeOpenCVParsesIt)
{
  // agex's own models are far below the limit.
  for (const char *name : {"agex_bonn.yml", "agex_bonn_sw.yml"})
  {
    const std::string path = std::string (AGEX_SOURCE_DIR) + "/data/models/" + name;
    const std::size_t bound = agex::yamlNestingBound (agex_test::readAll (path));
    std::cout << name << ": nesting bound " << bound << "\n";
    EXPECT_GT (bound, 3u);
    EXPECT_LT (bound, 200u) << name;
  }

  // 100,000 levels in each form OpenCV's parser recurses on; each overflowed its stack
  // (a crash, not an error) before the check. The line of the excess is named.
  TempDir dir;
  const std::string deep = dir.file ("deep.yml");
  const std::string header = "%YAML:1.0\n---\nformat: agex-model\n";
  const auto indentedMaps = [] (int levels) {
    std::string text;
    for (int i = 0; i < levels; ++i)
      text += std::string (static_cast<std::size_t> (i), ' ') + "k:\n";
    return text + std::string (static_cast<std::size_t> (levels), ' ') + "x\n";
  };
  for (const std::string &body :
       {"a: " + std::string (100000, '['), "a: " + repeat ("{a:", 100000), "a:\n " + repeat ("- ", 100000) + "x\n",
        "a: " + repeat ("a: ", 100000) + "x\n", indentedMaps (3000),
        "a: " + repeat ("[ \"]\", ", 100000)})
  {
    agex_test::writeAll (deep, header + body + "\nend: agex-model\n");
    SCOPED_TRACE (body.substr (0, 40));
    expectModelError (deep, ": nested more than 1000 levels deep");
  }
  agex_test::writeAll (deep, header + "a: " + std::string (100000, '[') + "\n");
  expectModelError (deep, deep + ":4: nested");

  // The bound is a bound: on documents OpenCV parses, never below the depth of its tree,
  // whatever the strings, comments, flow continuation lines and block forms.
  const std::vector<std::string> documents = {
      "a: " + std::string (500, '[') + std::string (500, ']') + "\n",
      "a: " + repeat ("{a: ", 300) + "1" + std::string (300, '}') + "\n",
      "a:\n   " + repeat ("- ", 300) + "x\n",
      "a: " + repeat ("b: ", 200) + "x\n",
      indentedMaps (200),
      "a: " + repeat ("[ \"]\", ", 300) + std::string (300, ']') + "\n",
      "a: " + repeat ("[ ']]]', ", 300) + std::string (300, ']') + "\n",
      "a:\n  [ 1,\n    [ 2,\n   [ 3, [ 4 ] ] ] ]\nb: [ [ [\n  1 ] ] ]\n",
      "a:\n   - { x: [ 1,\n        2 ], y: { z: [ [ 3 ] ] } }\n   - { x: [ 1 ] }\n# [ [ [ [\nb: 1\n",
      "a: !!seq [ [ 1 ] ]\nb: \"[[[[\"\nc: '{{{{'\n",
      "--- " + std::string (100, '[') + std::string (100, ']') + "\n",
      "a:\n   - - - - [ { b: c } ]\n   - x\n",
  };
  int parsed = 0;
  for (const auto &body : documents)
  {
    const std::string yaml = "%YAML:1.0\n---\n" + body;
    SCOPED_TRACE (body.substr (0, 60));
    cv::FileStorage fs;
    try
    {
      fs.open (yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    }
    catch (const cv::Exception &)
    {
      continue;
    }
    if (!fs.isOpened ())
      continue;
    ++parsed;
    EXPECT_GE (agex::yamlNestingBound (yaml), treeDepth (fs.root ()));
    EXPECT_GT (treeDepth (fs.root ()), 2u);
  }
  EXPECT_GE (parsed, 10) << "most of the documents must be valid YAML for OpenCV, or the check proves little";
}

TEST (ModelFile, Base64BinaryNodesAreRefusedBeforeOpenCVParsesThem)
{
  // The model fuzzer's input on which OpenCV 4.6's parser loops for minutes (kept in
  // test/fuzz/regressions/model/); refused before parsing, with its line.
  const std::string kept = std::string (AGEX_SOURCE_DIR) + "/test/fuzz/regressions/model/base64_binary_loops_opencv_parser.yml";
  expectModelError (kept, kept + ":4: base64 data (!!binary)");
  TempDir dir;
  const std::string path = dir.file ("binary.yml");
  agex_test::writeAll (path, "%YAML:1.0\n---\nformat: agex-model\nweights: !!binary |\n  AAAA\nend: agex-model\n");
  expectModelError (path, path + ":4: base64 data (!!binary)");
}

TEST (ModelFile, DeepMetadataAndFifosAreRefused)
{
  const PatchClassifier &classifier = trainedClassifier ();
  TempDir dir;
  // Metadata JSON nested 100 deep: nlohmann parses it without recursing, but printing it
  // (as reports do) recurses, so it is bounded too.
  nlohmann::json deep = 1;
  for (int i = 0; i < 100; ++i)
    deep = nlohmann::json::array ({deep});
  const std::string path = dir.file ("deep_metadata.yml");
  classifier.save (path, {{"training", deep}});
  expectModelError (path, "metadata nested more than 64 levels deep");
  nlohmann::json fine = 1;
  for (int i = 0; i < 60; ++i)
    fine = nlohmann::json::array ({fine});
  classifier.save (path, {{"training", fine}});
  EXPECT_NO_THROW (PatchClassifier::load (path)) << "60 levels are fine";

  // A FIFO would block the reader until someone writes to it.
  const std::string fifo = dir.file ("fifo.yml");
  ASSERT_EQ (::mkfifo (fifo.c_str (), 0600), 0);
  expectModelError (fifo, "is a FIFO (named pipe), not a regular file");
}
}  // namespace

// BodyPartForest, BodyPartLabeling, PartModeEstimation and BodyPartForestTrainer:
// hand-built trees with known answers, PCL's text format (plain and bzip2, malformed and
// truncated files), PCL's published forests against a direct port of PCL's GPU evaluation,
// training on synthetic classes, model round trips and damage, label-cloud PCD round trip,
// strides, and bad input.

#include "test_support.h"

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_forest_trainer.h>
#include <agex/classification/body_part_labeling.h>
#include <agex/classification/part_modes.h>
#include <agex/io/frame_io.h>

#include <pcl/io/pcd_io.h>

#include <boost/crc.hpp>
#include <boost/iostreams/filter/bzip2.hpp>
#include <boost/iostreams/filtering_stream.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>

using agex::BodyPartForest;
using agex::ForestDepthImage;
using namespace agex_test;

namespace
{
using Tree = BodyPartForest::Tree;
using Node = BodyPartForest::Node;

Node
node (int du1, int dv1, int du2, int dv2, float threshold)
{
  Node n;
  n.du1 = static_cast<std::int16_t> (du1);
  n.dv1 = static_cast<std::int16_t> (dv1);
  n.du2 = static_cast<std::int16_t> (du2);
  n.dv2 = static_cast<std::int16_t> (dv2);
  n.threshold = threshold;
  return n;
}

/** A 20 x 10 frame: depth 1000 mm for u < 10, 2000 mm for u >= 10; every pixel foreground. */
ForestDepthImage
stepImage ()
{
  ForestDepthImage img;
  img.reset (20, 10, 0, 0, 20, 10);
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 20; ++u)
      img.set (u, v, u < 10 ? 1000 : 2000);
  return img;
}

/** Depth 2, PCL layout. Root: d(x + (4, 0) s) - d(x) > 500 (a step ahead on the right).
  * Left child: d(x + (-4, 0) s) - d(x) > -500 (no step down on the left). Right child:
  * d(x + (0, 5) s) - d(x) > 10. Leaves 0..3 are classes 0..3. */
Tree
twoLevelTree ()
{
  Tree t;
  t.depth = 2;
  t.complete = true;
  t.nodes = {node (4, 0, 0, 0, 500.f), node (-4, 0, 0, 0, -500.f), node (0, 5, 0, 0, 10.f)};
  t.leaf_labels = {0, 1, 2, 3};
  return t;
}

std::vector<BodyPartForest::ClassInfo>
fourClasses ()
{
  return {{"head", agex::kLabelHead}, {"hand", agex::kLabelHand}, {"foot", agex::kLabelFoot}, {"other_body", agex::kLabelOtherBody}};
}

pcl::Indices
allPixels (const ForestDepthImage &img)
{
  pcl::Indices all;
  for (int i = 0; i < img.frameWidth () * img.frameHeight (); ++i)
    all.push_back (i);
  return all;
}

std::string
pclTreeText (const Tree &t)
{
  std::ostringstream s;
  s << t.depth << "\n";
  for (const auto &n : t.nodes)
    s << n.du1 << " " << n.dv1 << " " << n.du2 << " " << n.dv2 << " " << static_cast<int> (n.threshold) << "\n";
  for (const auto l : t.leaf_labels)
    s << static_cast<int> (l) << "\n";
  return s.str ();
}

std::string
bzip2 (const std::string &text)
{
  std::ostringstream out;
  {
    boost::iostreams::filtering_ostream z;
    z.push (boost::iostreams::bzip2_compressor ());
    z.push (out);
    z << text;
  }
  return out.str ();
}

/** Runs fn and returns the ModelError's message ("" if nothing was thrown). */
template <typename Fn>
std::string
modelError (Fn fn)
{
  try
  {
    fn ();
  }
  catch (const agex::ModelError &e)
  {
    return e.what ();
  }
  return "";
}

// --- a direct port of PCL's GPU evaluation (multi_tree.cu), for comparison -------------------

/** tex2D on a uint16 texture, point sampling, clamp addressing: texel floor (x), floor (y). */
int
tex (const std::vector<std::uint16_t> &d, int W, int H, float x, float y)
{
  int u = static_cast<int> (std::floor (x)), v = static_cast<int> (std::floor (y));
  u = std::clamp (u, 0, W - 1);
  v = std::clamp (v, 0, H - 1);
  return d[static_cast<std::size_t> (v) * W + u];
}

/** evaluateTree<false>: float scale = f / depth; u + du * scale as one fused multiply-add. */
int
pclTreeLabel (const Tree &t, const std::vector<std::uint16_t> &d, int W, int H, int u, int v, float f)
{
  const int depth = tex (d, W, H, static_cast<float> (u), static_cast<float> (v));
  const float scale = f / static_cast<float> (depth);
  int nid = 0;
  for (int level = 0; level < t.depth; ++level)
  {
    const Node &n = t.nodes[nid];
    const int d1 = tex (d, W, H, std::fma (static_cast<float> (n.du1), scale, static_cast<float> (u)),
                        std::fma (static_cast<float> (n.dv1), scale, static_cast<float> (v)));
    const int d2 = tex (d, W, H, std::fma (static_cast<float> (n.du2), scale, static_cast<float> (u)),
                        std::fma (static_cast<float> (n.dv2), scale, static_cast<float> (v)));
    nid = (d1 - d2 > static_cast<int> (n.threshold)) ? nid * 2 + 2 : nid * 2 + 1;
  }
  return t.leaf_labels[nid - static_cast<int> (t.nodes.size ())];
}

/** KernelCUDA_MultiTreePass + KernelCUDA_MultiTreeMerge at pixel (u, v) of a full frame. */
int
pclMergedLabel (const std::vector<Tree> &trees, const std::vector<std::uint16_t> &d, int W, int H, int u, int v, float f)
{
  auto labels = [&] (int x, int y, char *out) {
    for (std::size_t t = 0; t < trees.size (); ++t)
      out[t] = d[static_cast<std::size_t> (y) * W + x] == 65535 ? 29 : static_cast<char> (pclTreeLabel (trees[t], d, W, H, x, y, f));
  };
  char bins[32] = {};
  char mine[8];
  labels (u, v, mine);
  for (std::size_t t = 0; t < trees.size (); ++t)
    bins[static_cast<int> (mine[t])]++;
  int maxId = 0, maxOther = -1;
  char maxVal = bins[0];
  for (int i = 1; i < 32; ++i)
  {
    if (bins[i] == maxVal)
      maxOther = i;
    if (bins[i] > maxVal)
    {
      maxId = i;
      maxOther = -1;
      maxVal = bins[i];
    }
  }
  if (maxOther == -1)
    return maxId;
  const int depth = d[static_cast<std::size_t> (v) * W + u];
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
    {
      const int x = std::clamp (u + i, 0, W - 1), y = std::clamp (v + j, 0, H - 1);
      const int dn = d[static_cast<std::size_t> (y) * W + x];
      if (std::abs (depth - dn) >= 50)
        continue;
      char theirs[8];
      labels (x, y, theirs);
      for (std::size_t t = 0; t < trees.size (); ++t)
        bins[static_cast<int> (theirs[t])]++;
    }
  maxId = 0;
  maxVal = bins[0];
  for (int i = 1; i < 32; ++i)
    if (bins[i] > maxVal)
    {
      maxId = i;
      maxVal = bins[i];
    }
  return maxId;
}

/** smoothKernel (patch 5, 300 mm, 25 parts) at (u, v) of a full label image. */
int
pclSmoothedLabel (const std::vector<int> &labels, const std::vector<std::uint16_t> &d, int W, int u, int v)
{
  int hist[32] = {};
  const int dc = d[static_cast<std::size_t> (v) * W + u];
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx)
    {
      const std::size_t k = static_cast<std::size_t> (v + dy) * W + (u + dx);
      if (std::abs (d[k] - dc) < 300 && labels[k] >= 0 && labels[k] < 25)
        ++hist[labels[k]];
    }
  int max_label = labels[static_cast<std::size_t> (v) * W + u], max_value = 0;
  for (int l = 0; l < 32; ++l)
    if (max_value < hist[l])
    {
      max_value = hist[l];
      max_label = l;
    }
  return max_label;
}

/** Random complete trees of PCL's kind: offsets up to +-300, thresholds +-400, labels 0-24. */
std::vector<Tree>
randomPclTrees (int count, int depth, std::uint32_t seed)
{
  std::mt19937 rng (seed);
  std::uniform_int_distribution<int> off (-300, 300), thr (-400, 400), lab (0, 24);
  std::vector<Tree> trees (count);
  for (auto &t : trees)
  {
    t.depth = depth;
    t.complete = true;
    t.nodes.resize ((std::size_t (1) << depth) - 1);
    for (auto &n : t.nodes)
      n = node (off (rng), off (rng), off (rng) / 2, off (rng) / 2, static_cast<float> (thr (rng)));
    t.leaf_labels.resize (std::size_t (1) << depth);
    for (auto &l : t.leaf_labels)
      l = static_cast<std::uint8_t> (lab (rng) % 4 == 0 ? 14 : lab (rng));  // many hands: ties
  }
  return trees;
}

/** A synthetic person-like depth scene (mm): a blob and limbs in front of nothing. */
Cloud::Ptr
syntheticPerson (int W, int H, std::uint32_t seed)
{
  Camera cam;
  cam.width = W;
  cam.height = H;
  cam.cx = W / 2.0 - 0.5;
  cam.cy = H / 2.0 - 0.5;
  std::mt19937 rng (seed);
  std::uniform_real_distribution<double> jitter (-0.05, 0.05);
  Figure f = makeStar (Eigen::Vector2d (jitter (rng), jitter (rng)), 2.0 + 4 * jitter (rng), 5, 0.5, 0.07, 0.18);
  auto cloud = rasterise ({f}, cam);
  // Depth texture (a gentle slope) so that depth differences inside the body matter.
  for (auto &p : cloud->points)
    if (std::isfinite (p.z))
      p.z += static_cast<float> (0.05 * std::sin (13.0 * p.x) + 0.03 * std::cos (17.0 * p.y));
  return cloud;
}

pcl::Indices
finiteIndices (const Cloud &cloud)
{
  pcl::Indices idx;
  for (std::size_t i = 0; i < cloud.size (); ++i)
    if (std::isfinite (cloud[i].z))
      idx.push_back (static_cast<int> (i));
  return idx;
}
}  // namespace

// --- hand-built trees --------------------------------------------------------------------------

TEST (BodyPartForest, TwoLevelTreeKnownAnswers)
{
  const BodyPartForest forest (fourClasses (), {twoLevelTree ()}, 525.f, BodyPartForest::VoteRule::PclMajority, -1);
  const ForestDepthImage img = stepImage ();
  // At 1000 mm the scale is 1000 / 1000 = 1: offset 4 probes 4 pixels away.
  // (8, 5): root probe (12, 5) = 2000, 2000 - 1000 > 500: right; right child probe (8, 10)
  // clamps to row 9 (depth 1000): 0 > 10 false: left of the right child = leaf 2.
  // (2, 5): root probe (6, 5) = 1000: left; left child probe (-2, 5) clamps to column 0:
  // 0 > -500: right = leaf 1.
  // (15, 5), depth 2000, scale 0.5: probe (17, 5) = 2000: left; probe (13, 5) = 2000: leaf 1.
  // (10, 5): probe (12, 5): left; probe (8, 5) = 1000, -1000 > -500 false: leaf 0.
  const int expected[][3] = {{8, 5, 2}, {2, 5, 1}, {15, 5, 1}, {10, 5, 0}};
  for (const auto &e : expected)
  {
    float su, sv;
    BodyPartForest::scales (1000.f, 1000.f, img.at (e[0], e[1]), su, sv);
    EXPECT_EQ (forest.leafOf (0, img, e[0], e[1], su, sv), e[2]) << "pixel " << e[0] << "," << e[1];
  }
  BodyPartForest::Evaluation out;
  pcl::Indices pixels;
  for (const auto &e : expected)
    pixels.push_back (e[1] * 20 + e[0]);
  ASSERT_TRUE (forest.evaluate (img, pixels, BodyPartForest::EvaluationOptions (), out));
  for (std::size_t i = 0; i < pixels.size (); ++i)
  {
    EXPECT_EQ (out.labels[i], expected[i][2]);
    EXPECT_FLOAT_EQ (out.probabilities[i * 4 + expected[i][2]], 1.f);  // one tree: a full vote
  }
  // At half the reference focal length the offsets halve: (7, 5) probes (11, 5) = 2000 at the
  // reference focal (right, then leaf 2) but (9, 5) = 1000 at half of it (left; the left
  // child probes (5, 5): 0 > -500, leaf 1).
  ASSERT_TRUE (forest.evaluate (img, {5 * 20 + 7}, BodyPartForest::EvaluationOptions (), out));
  EXPECT_EQ (out.labels[0], 2);
  BodyPartForest::EvaluationOptions half;
  half.fx = half.fy = 262.5f;
  ASSERT_TRUE (forest.evaluate (img, {5 * 20 + 7}, half, out));
  EXPECT_EQ (out.labels[0], 1);
}

TEST (BodyPartForest, SparseTreeDistributionsAveraged)
{
  // Root splits on the step; two leaves with distributions; a second tree is a single leaf.
  Tree a;
  a.depth = 1;
  a.nodes = {node (4, 0, 0, 0, 500.f), Node (), Node ()};
  a.children = {1, -1, -2};
  a.leaf_labels = {0, 1};
  a.leaf_distributions = {0.6f, 0.4f, 0.f, 0.f, 0.f, 0.2f, 0.f, 0.8f};
  Tree b;
  b.depth = 0;
  b.nodes = {Node ()};
  b.children = {-1};
  b.leaf_labels = {3};
  b.leaf_distributions = {0.f, 0.f, 0.f, 1.f};
  const BodyPartForest forest (fourClasses (), {a, b}, 525.f, BodyPartForest::VoteRule::Average, -1);
  BodyPartForest::Evaluation out;
  ASSERT_TRUE (forest.evaluate (stepImage (), {5 * 20 + 8, 5 * 20 + 2}, BodyPartForest::EvaluationOptions (), out));
  // (8, 5) goes right: (0, .2, 0, .8) and (0, 0, 0, 1) average to (0, .1, 0, .9).
  EXPECT_FLOAT_EQ (out.probabilities[1], 0.1f);
  EXPECT_FLOAT_EQ (out.probabilities[3], 0.9f);
  EXPECT_EQ (out.labels[0], 3);
  // (2, 5) goes left: (.6, .4, 0, 0) and (0, 0, 0, 1): (.3, .2, 0, .5).
  EXPECT_FLOAT_EQ (out.probabilities[4 + 0], 0.3f);
  EXPECT_FLOAT_EQ (out.probabilities[4 + 3], 0.5f);
  EXPECT_EQ (out.labels[1], 3);
}

TEST (BodyPartForest, PclTieBreakUsesNeighbours)
{
  // A 20 x 10 image, 1000 mm for u < 10 and 1020 mm (within PCL's 50 mm) for u >= 10. Tree 0
  // tests d(x) - d(x - 1 px) > 10: only the column u = 10 goes right (label 1), the rest left
  // (label 0); trees 1 and 2 always vote 1 and 2. So u = 10 has votes 1, 1, 2 (label 1) and
  // every other pixel a tie 0, 1, 2, broken by its 3x3 neighbourhood's votes (itself again):
  // at u = 5 all neighbours tie as well (10 votes each): the lowest label, 0; at u = 9 and
  // u = 11 the column u = 10 adds three more votes for 1.
  ForestDepthImage img;
  img.reset (20, 10, 0, 0, 20, 10);
  for (int v = 0; v < 10; ++v)
    for (int u = 0; u < 20; ++u)
      img.set (u, v, u < 10 ? 1000 : 1020);
  auto constant = [] (int label) {
    Tree t;
    t.depth = 1;
    t.complete = true;
    t.nodes = {node (0, 0, 0, 0, 0.f)};  // 0 > 0 is false: always left
    t.leaf_labels = {static_cast<std::uint8_t> (label), static_cast<std::uint8_t> (label)};
    return t;
  };
  Tree t0;
  t0.depth = 1;
  t0.complete = true;
  t0.nodes = {node (0, 0, -1, 0, 10.f)};
  t0.leaf_labels = {0, 1};
  // Reference focal 1000 and no focal given: the scale at 1000 mm is 1 (probe x - 1).
  const BodyPartForest forest ({{"a", 0}, {"b", 1}, {"c", 2}}, {t0, constant (1), constant (2)}, 1000.f,
                               BodyPartForest::VoteRule::PclMajority, -1);
  BodyPartForest::Evaluation out;
  ASSERT_TRUE (forest.evaluate (img, allPixels (img), BodyPartForest::EvaluationOptions (), out));
  EXPECT_EQ (out.labels[5 * 20 + 10], 1);
  EXPECT_EQ (out.labels[5 * 20 + 5], 0);
  EXPECT_EQ (out.labels[5 * 20 + 9], 1);
  EXPECT_EQ (out.labels[5 * 20 + 11], 1);
  EXPECT_EQ (out.labels[5 * 20 + 15], 0);
  EXPECT_NEAR (out.probabilities[(5 * 20 + 5) * 3 + 0], 1.f / 3.f, 1e-6f);
  EXPECT_NEAR (out.probabilities[(5 * 20 + 10) * 3 + 1], 2.f / 3.f, 1e-6f);
}

TEST (BodyPartForest, BackgroundAndNoDataAreNotLabelled)
{
  const BodyPartForest forest (fourClasses (), {twoLevelTree ()}, 525.f, BodyPartForest::VoteRule::PclMajority, -1);
  ForestDepthImage img = stepImage ();
  img.set (3, 3, ForestDepthImage::kNoData);
  img.set (4, 3, ForestDepthImage::kBackground);
  BodyPartForest::Evaluation out;
  ASSERT_TRUE (forest.evaluate (img, {3 * 20 + 3, 3 * 20 + 4, -5, 200, 1000000}, BodyPartForest::EvaluationOptions (), out));
  for (const int l : out.labels)
    EXPECT_EQ (l, -1);
  EXPECT_EQ (out.evaluated, 0u);
}

TEST (BodyPartForest, FmaKernelMatchesGenericKernel)
{
  const auto trees = randomPclTrees (3, 10, 7);
  const BodyPartForest forest (BodyPartForest::pclClasses (), trees, 525.f, BodyPartForest::VoteRule::PclMajority, 29);
  const auto cloud = syntheticPerson (160, 120, 3);
  const pcl::Indices fg = finiteIndices (*cloud);
  ForestDepthImage img;
  img.build (*cloud, fg);
  BodyPartForest::EvaluationOptions fast, generic;
  generic.generic_kernel = true;
  for (const float f : {525.f, 210.f, 1000.f / 3.f})
  {
    fast.fx = fast.fy = generic.fx = generic.fy = f;
    BodyPartForest::Evaluation a, b;
    ASSERT_TRUE (forest.evaluate (img, fg, fast, a));
    ASSERT_TRUE (forest.evaluate (img, fg, generic, b));
    EXPECT_EQ (a.labels, b.labels);
    EXPECT_EQ (a.probabilities, b.probabilities);
  }
}

TEST (BodyPartForest, MatchesPclGpuEvaluationOnSyntheticScene)
{
  // Random PCL-like trees (ties are frequent: many leaves are hands) on a synthetic person,
  // everything else background: our labels against the port of multi_tree.cu, and with PCL's
  // smoothing against the port of smooth.cu.
  const auto trees = randomPclTrees (3, 12, 11);
  const BodyPartForest forest (BodyPartForest::pclClasses (), trees, 525.f, BodyPartForest::VoteRule::PclMajority, 29);
  const auto cloud = syntheticPerson (160, 120, 5);
  const pcl::Indices fg = finiteIndices (*cloud);
  ForestDepthImage img;
  img.build (*cloud, fg);
  const int W = 160, H = 120;
  std::vector<std::uint16_t> full (W * H, 65535);
  for (const auto i : fg)
    full[i] = ForestDepthImage::toMillimetres ((*cloud)[i].x, (*cloud)[i].y, (*cloud)[i].z);
  BodyPartForest::EvaluationOptions options;
  BodyPartForest::Evaluation out;
  ASSERT_TRUE (forest.evaluate (img, fg, options, out));
  std::vector<int> reference (W * H, 29);
  int ties = 0;
  for (std::size_t j = 0; j < fg.size (); ++j)
  {
    const int u = fg[j] % W, v = fg[j] / W;
    reference[fg[j]] = pclMergedLabel (trees, full, W, H, u, v, 1000.f);
    ASSERT_EQ (out.labels[j], reference[fg[j]]) << "pixel " << u << "," << v;
    std::set<int> votes;
    for (const auto &t : trees)
      votes.insert (pclTreeLabel (t, full, W, H, u, v, 1000.f));
    ties += votes.size () == 3 ? 1 : 0;
  }
  EXPECT_GT (ties, 20) << "the scene should exercise the tie-break";
  options.pcl_smoothing = true;
  ASSERT_TRUE (forest.evaluate (img, fg, options, out));
  for (std::size_t j = 0; j < fg.size (); ++j)
  {
    const int u = fg[j] % W, v = fg[j] / W;
    if (u < 2 || v < 2 || u >= W - 2 || v >= H - 2)
      continue;
    ASSERT_EQ (out.labels[j], pclSmoothedLabel (reference, full, W, u, v)) << "pixel " << u << "," << v;
  }
}

TEST (BodyPartForest, StrideCopiesOrLeavesUnlabelled)
{
  const auto trees = randomPclTrees (3, 8, 2);
  BodyPartForest forest (BodyPartForest::pclClasses (), trees, 525.f, BodyPartForest::VoteRule::Average, 29);
  const auto cloud = syntheticPerson (160, 120, 9);
  const pcl::Indices fg = finiteIndices (*cloud);
  ForestDepthImage img;
  img.build (*cloud, fg);
  BodyPartForest::EvaluationOptions one, copy, none;
  copy.stride = none.stride = 2;
  none.fill = BodyPartForest::StrideFill::Unlabelled;
  BodyPartForest::Evaluation a, b, c;
  ASSERT_TRUE (forest.evaluate (img, fg, one, a));
  ASSERT_TRUE (forest.evaluate (img, fg, copy, b));
  ASSERT_TRUE (forest.evaluate (img, fg, none, c));
  EXPECT_EQ (a.evaluated, fg.size ());
  EXPECT_LT (b.evaluated, fg.size () / 3);  // about a quarter
  EXPECT_EQ (b.evaluated, c.evaluated);
  std::size_t labelled = 0;
  for (std::size_t j = 0; j < fg.size (); ++j)
  {
    EXPECT_GE (b.labels[j], 0) << "Copy labels every foreground pixel";
    if (c.labels[j] < 0)
      continue;
    ++labelled;
    // An evaluated pixel gives what stride 1 gives there (the Average vote has no neighbours).
    EXPECT_EQ (c.labels[j], a.labels[j]);
    EXPECT_EQ (b.labels[j], a.labels[j]);
  }
  EXPECT_EQ (labelled, c.evaluated);
  // Copied pixels take their cell's first foreground pixel (row-major) result.
  const int W = 160;
  std::map<int, std::size_t> first;
  for (std::size_t j = 0; j < fg.size (); ++j)
  {
    const int key = (fg[j] / W / 2) * 1000 + (fg[j] % W) / 2;
    if (!first.count (key))
      first[key] = j;  // fg is in row-major order... within a cell, rows first
  }
  for (std::size_t j = 0; j < fg.size (); ++j)
  {
    const int key = (fg[j] / W / 2) * 1000 + (fg[j] % W) / 2;
    EXPECT_EQ (b.labels[j], a.labels[first[key]]);
  }
  // PCL's vote with a stride: ties look at the neighbouring cells; still every pixel labelled.
  forest.setVoteRule (BodyPartForest::VoteRule::PclMajority);
  ASSERT_TRUE (forest.evaluate (img, fg, copy, b));
  for (const int l : b.labels)
    EXPECT_GE (l, 0);
  EXPECT_EQ (b.evaluated, c.evaluated) << "no pixel is run twice with a stride";
}

TEST (BodyPartForest, ThreadsGiveTheSameResult)
{
  const BodyPartForest forest (BodyPartForest::pclClasses (), randomPclTrees (3, 10, 4), 525.f,
                               BodyPartForest::VoteRule::PclMajority, 29);
  const auto cloud = syntheticPerson (320, 240, 2);
  const pcl::Indices fg = finiteIndices (*cloud);
  ForestDepthImage img;
  img.build (*cloud, fg);
  BodyPartForest::EvaluationOptions one, two;
  two.threads = 2;
  one.pcl_smoothing = two.pcl_smoothing = true;
  BodyPartForest::Evaluation a, b;
  ASSERT_TRUE (forest.evaluate (img, fg, one, a));
  ASSERT_TRUE (forest.evaluate (img, fg, two, b));
  EXPECT_EQ (a.labels, b.labels);
  EXPECT_EQ (a.probabilities, b.probabilities);
}

TEST (BodyPartForest, DepthImageBuildAndDilation)
{
  Cloud cloud (6, 5, pcl::PointXYZ (0.f, 0.f, 1.5f));
  cloud (2, 2).z = std::numeric_limits<float>::quiet_NaN ();
  ForestDepthImage img;
  img.build (cloud, {2 * 6 + 2, 2 * 6 + 3});
  EXPECT_EQ (img.at (2, 2), ForestDepthImage::kNoData);  // a given pixel without depth
  EXPECT_EQ (img.at (3, 2), 1500);
  EXPECT_EQ (img.at (4, 2), ForestDepthImage::kBackground);
  EXPECT_EQ (img.at (0, 0), ForestDepthImage::kBackground);  // outside the window: clamped to background
  img.build (cloud, {2 * 6 + 3}, 1);
  EXPECT_EQ (img.at (4, 3), 1500);  // the ring keeps its depth
  EXPECT_EQ (img.at (2, 2), ForestDepthImage::kNoData);
  EXPECT_EQ (img.at (5, 2), ForestDepthImage::kBackground);
  EXPECT_EQ (ForestDepthImage::toMillimetres (0.f, 0.f, 1.5007f), 1500);  // truncation, as PCL
  EXPECT_EQ (ForestDepthImage::toMillimetres (0.f, 0.f, -1.f), ForestDepthImage::kNoData);
  EXPECT_EQ (ForestDepthImage::toMillimetres (0.f, 0.f, 70.f), ForestDepthImage::kNoData);
  img.build (cloud, {});
  EXPECT_TRUE (img.empty ());
}

// --- PCL's text format -------------------------------------------------------------------------

TEST (BodyPartForest, PclTreeFilesPlainAndBzip2)
{
  TempDir dir;
  const Tree t = twoLevelTree ();
  fs::create_directories (dir.path () / "a");
  fs::create_directories (dir.path () / "b");
  writeAll (dir.file ("a/tree_2.txt"), pclTreeText (t));
  writeAll (dir.file ("b/tree_2.txt.bz2"), bzip2 (pclTreeText (t)));
  writeAll (dir.file ("b/LICENSE"), "not a tree");
  const auto plain = BodyPartForest::load (dir.file ("a/tree_2.txt"));
  const auto packed = BodyPartForest::load (dir.file ("b/tree_2.txt.bz2"));
  const auto both = BodyPartForest::load (dir.path ().string ());
  ASSERT_EQ (both->trees ().size (), 2u);
  EXPECT_EQ (BodyPartForest::findPclTreeFiles (dir.path ().string ()),
             (std::vector<std::string>{dir.file ("a/tree_2.txt"), dir.file ("b/tree_2.txt.bz2")}));
  for (const auto &f : {plain, packed})
  {
    ASSERT_EQ (f->trees ().size (), 1u);
    const Tree &r = f->trees ()[0];
    EXPECT_TRUE (r.complete);
    EXPECT_EQ (r.depth, 2);
    EXPECT_EQ (r.leaf_labels, t.leaf_labels);
    ASSERT_EQ (r.nodes.size (), 3u);
    EXPECT_EQ (r.nodes[2].dv1, 5);
    EXPECT_EQ (r.nodes[1].threshold, -500.f);
    EXPECT_EQ (f->numClasses (), 32);
    EXPECT_EQ (f->voteRule (), BodyPartForest::VoteRule::PclMajority);
    EXPECT_EQ (f->backgroundClass (), 29);
  }
  // PCL's label mapping.
  EXPECT_EQ (plain->classPart (19), agex::kLabelHead);
  EXPECT_EQ (plain->classPart (22), agex::kLabelHead);
  EXPECT_EQ (plain->classPart (14), agex::kLabelHand);
  EXPECT_EQ (plain->classPart (18), agex::kLabelHand);
  EXPECT_EQ (plain->classPart (0), agex::kLabelFoot);
  EXPECT_EQ (plain->classPart (4), agex::kLabelFoot);
  EXPECT_EQ (plain->classPart (10), agex::kLabelOtherBody);
  EXPECT_EQ (plain->classPart (24), agex::kLabelOtherBody);
  EXPECT_EQ (plain->classPart (29), agex::kLabelNone);
  EXPECT_EQ (plain->classPart (31), agex::kLabelNone);
  EXPECT_EQ (plain->classes ()[18].name, "Lhand");
  // The loaded tree labels like the hand-built one.
  const ForestDepthImage img = stepImage ();
  float su, sv;
  BodyPartForest::scales (1000.f, 1000.f, 1000, su, sv);
  EXPECT_EQ (plain->leafOf (0, img, 8, 5, su, sv), 2);
  EXPECT_EQ (packed->leafOf (0, img, 2, 5, su, sv), 1);
  // An empty directory has no trees.
  fs::create_directories (dir.path () / "empty");
  EXPECT_NE (modelError ([&] { BodyPartForest::load (dir.file ("empty")); }).find ("no PCL tree files"), std::string::npos);
}

TEST (BodyPartForest, MalformedPclTreeFilesNameFileAndLine)
{
  TempDir dir;
  const std::string good = pclTreeText (twoLevelTree ());
  // good with line n (1-based) replaced.
  auto withLine = [&] (int n, const std::string &line) {
    std::istringstream in (good);
    std::string l, out;
    for (int i = 1; std::getline (in, l); ++i)
      out += (i == n ? line : l) + "\n";
    return out;
  };
  struct Case
  {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
    {"empty", "", ":1: empty"},
    {"words", withLine (1, "two"), ":1: expected the tree depth"},
    {"deep", withLine (1, "25"), ":1: tree depth 25 out of range"},
    {"zero", withLine (1, "0"), ":1: tree depth 0 out of range"},
    {"four_fields", withLine (2, "1 2 3 4"), ":2: expected a node"},
    {"six_fields", withLine (3, "1 2 3 4 5 6"), ":3: expected a node"},
    {"int16", withLine (4, "1 2 3 4 40000"), ":4: expected a node"},
    {"float", withLine (2, "1 2 3 4 5.5"), ":2: expected a node"},
    {"label32", withLine (7, "32"), ":7: expected a leaf"},
    {"negative_label", withLine (6, "-1"), ":6: expected a leaf"},
    {"missing_leaves", "2\n0 0 0 0 0\n0 0 0 0 0\n0 0 0 0 0\n0\n1\n", "truncated"},
    {"missing_nodes", "2\n0 0 0 0 0\n", "truncated"},
    {"no_newline", good.substr (0, good.size () - 1), "truncated"},
    {"trailing", good + "7\n", ":9: unexpected content"},
  };
  for (const auto &c : cases)
  {
    const std::string path = dir.file (c.name + ".txt");
    writeAll (path, c.text);
    const std::string message = modelError ([&] { BodyPartForest::load (path); });
    EXPECT_NE (message.find (path), std::string::npos) << c.name << ": " << message;
    EXPECT_NE (message.find (c.expect), std::string::npos) << c.name << ": " << message;
    // The same text compressed: the same message, naming the .bz2 file.
    const std::string packed = dir.file (c.name + ".txt.bz2");
    if (!c.text.empty ())
    {
      writeAll (packed, bzip2 (c.text));
      const std::string m2 = modelError ([&] { BodyPartForest::load (packed); });
      EXPECT_NE (m2.find (packed), std::string::npos) << c.name << ": " << m2;
    }
  }
  // Trailing blank lines and CRLF line ends are fine.
  writeAll (dir.file ("crlf.txt"), std::regex_replace (good, std::regex ("\n"), "\r\n") + "\n\n");
  EXPECT_NO_THROW (BodyPartForest::load (dir.file ("crlf.txt")));
  // Damaged and truncated bzip2 streams.
  const std::string z = bzip2 (good);
  std::string damaged = z;
  damaged[z.size () / 2] = static_cast<char> (damaged[z.size () / 2] ^ 0x55);
  writeAll (dir.file ("damaged.txt.bz2"), damaged);
  EXPECT_NE (modelError ([&] { BodyPartForest::load (dir.file ("damaged.txt.bz2")); }).find ("damaged.txt.bz2"),
             std::string::npos);
  writeAll (dir.file ("cut.txt.bz2"), z.substr (0, z.size () - 10));
  EXPECT_NE (modelError ([&] { BodyPartForest::load (dir.file ("cut.txt.bz2")); }).find ("cut.txt.bz2"), std::string::npos);
  // A plain file too short for its declared depth is refused before anything is allocated.
  writeAll (dir.file ("claims.txt"), "24\n0 0 0 0 0\n");
  EXPECT_NE (modelError ([&] { BodyPartForest::load (dir.file ("claims.txt")); }).find ("truncated"), std::string::npos);
  EXPECT_NE (modelError ([&] { BodyPartForest::load (dir.file ("missing.txt")); }).find ("missing.txt"), std::string::npos);
}

TEST (BodyPartForest, PclForestTooLargeIsRefusedBeforeReading)
{
  // 9 KB of bzip2 can hold a depth-24 tree (16.7 M nodes, 201 MB of text): the declared
  // depths are summed first, so the third such file is refused before any tree is read.
  TempDir dir;
  fs::create_directories (dir.path () / "forest");
  for (int i = 0; i < 20; ++i)
    writeAll (dir.file ("forest/tree_" + std::to_string (10 + i) + ".txt.bz2"), bzip2 ("24\n0 0 0 0 0\n"));
  const auto start = std::chrono::steady_clock::now ();
  const std::string message = modelError ([&] { BodyPartForest::load (dir.file ("forest")); });
  EXPECT_LT (std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count (), 2.0);
  EXPECT_NE (message.find (dir.file ("forest/tree_12.txt.bz2")), std::string::npos) << message;
  EXPECT_NE (message.find ("kMaxForestNodes"), std::string::npos) << message;
  // Padded lines compress to nothing: a tree's text is bounded by its lines.
  std::string padded = pclTreeText (twoLevelTree ());
  for (int i = 0; i < 1000; ++i)
    padded += std::string (4000, ' ') + "\n";
  writeAll (dir.file ("padded.txt.bz2"), bzip2 (padded));
  const std::string m2 = modelError ([&] { BodyPartForest::load (dir.file ("padded.txt.bz2")); });
  EXPECT_NE (m2.find ("padded.txt.bz2"), std::string::npos) << m2;
  EXPECT_NE (m2.find ("bytes of text for a depth-2 tree"), std::string::npos) << m2;
}

TEST (BodyPartForest, PclTreeSearchIsBounded)
{
  TempDir dir;
  // A tree file 40 levels down: the search refuses the depth, naming the directory.
  fs::path deep = dir.path () / "deep";
  for (int i = 0; i < 40; ++i)
    deep /= "d";
  fs::create_directories (deep);
  writeAll ((deep / "tree_2.txt").string (), pclTreeText (twoLevelTree ()));
  std::string message = modelError ([&] { BodyPartForest::findPclTreeFiles (dir.file ("deep")); });
  EXPECT_NE (message.find (dir.file ("deep") + ": folders nested deeper than 16 levels"), std::string::npos) << message;
  // 15 folders down it is found.
  fs::path ok = dir.path () / "ok";
  for (int i = 0; i < 15; ++i)
    ok /= "d";
  fs::create_directories (ok);
  writeAll ((ok / "tree_2.txt").string (), pclTreeText (twoLevelTree ()));
  EXPECT_EQ (BodyPartForest::findPclTreeFiles (dir.file ("ok")).size (), 1u);
  // A symlink loop ends at the same bound.
  fs::create_directories (dir.path () / "loop");
  fs::create_directory_symlink ("..", dir.path () / "loop" / "up");
  message = modelError ([&] { BodyPartForest::findPclTreeFiles (dir.file ("loop")); });
  EXPECT_NE (message.find ("nested deeper than"), std::string::npos) << message;
}

// --- PCL's published forests ----------------------------------------------------------------

TEST (BodyPartForest, PclForestsMatchPclOnABonnFrame)
{
  const std::string forests = sharedData ("pcl_people");
  const std::string frame_path = sharedData ("bonn/depth/7/031.png");
  AGEX_REQUIRE_SHARED_FILE (forests + "/forest1/tree_20.txt.bz2", "PCL's people forests (../shared/data/pcl_people)");
  AGEX_REQUIRE_BONN (frame_path);
  const auto forest = BodyPartForest::load (forests);
  ASSERT_EQ (forest->trees ().size (), 3u);
  for (const auto &t : forest->trees ())
  {
    EXPECT_EQ (t.depth, 20);
    EXPECT_EQ (t.nodes.size (), (1u << 20) - 1);
  }
  const agex::Frame frame = agex::loadFrame (frame_path);
  // The person: the apps' crop box (doc/pipeline.md) on the full 640x480 frame.
  pcl::Indices person;
  for (std::size_t i = 0; i < frame.cloud->size (); ++i)
  {
    const auto &p = (*frame.cloud)[i];
    if (std::isfinite (p.z) && p.z > 1.3f && p.z < 2.6f && std::abs (p.x) < 0.75f && p.y > -1.5f && p.y < 0.9f)
      person.push_back (static_cast<int> (i));
  }
  ASSERT_GT (person.size (), 10000u);
  const int W = 640, H = 480;
  std::vector<std::uint16_t> full (W * H, 65535);
  for (const auto i : person)
    full[i] = ForestDepthImage::toMillimetres ((*frame.cloud)[i].x, (*frame.cloud)[i].y, (*frame.cloud)[i].z);
  agex::BodyPartLabeling<pcl::PointXYZ> labeling;
  labeling.setInputCloud (frame.cloud);
  labeling.setIndices (std::make_shared<pcl::Indices> (person));
  labeling.setForest (forest);
  labeling.setFocalLength (525.f);
  pcl::PointCloud<agex::BodyPartLabelPoint> labels;
  ASSERT_TRUE (labeling.compute (labels));
  const auto &ev = labeling.getEvaluation ();
  std::size_t checked = 0, mismatches = 0;
  std::array<int, 5> parts{};
  for (std::size_t j = 0; j < person.size (); j += 13)  // every 13th pixel: the port is slow
  {
    const int u = person[j] % W, v = person[j] / W;
    mismatches += ev.labels[j] != pclMergedLabel (forest->trees (), full, W, H, u, v, 1000.f) ? 1 : 0;
    ++checked;
  }
  for (const auto i : person)
    ++parts[labels[i].label + 1];
  EXPECT_EQ (mismatches, 0u) << "of " << checked;
  // Every part appears, the body dominates, and no person pixel is left unlabelled.
  EXPECT_EQ (parts[0], 0);
  for (int p = 1; p <= 4; ++p)
    EXPECT_GT (parts[p], 100) << agex::labelPartName (p - 1);
  EXPECT_GT (parts[4], static_cast<int> (person.size ()) / 2);
}

// --- our model file ----------------------------------------------------------------------------

TEST (BodyPartForest, ModelRoundTripAndDamage)
{
  TempDir dir;
  Tree sparse;
  sparse.depth = 1;
  sparse.nodes = {node (4, 0, -3, 2, 12.5f), Node (), Node ()};
  sparse.children = {1, -1, -2};
  sparse.leaf_labels = {0, 3};
  sparse.leaf_distributions = {0.7f, 0.1f, 0.1f, 0.1f, 0.f, 0.f, 0.25f, 0.75f};
  const BodyPartForest original (fourClasses (), {twoLevelTree (), sparse}, 210.f, BodyPartForest::VoteRule::Average, -1);
  const std::string path = dir.file ("forest.agexforest");
  original.save (path, "{\"note\": 1}");
  const auto loaded = BodyPartForest::load (path);
  EXPECT_EQ (loaded->metadata (), "{\"note\": 1}");
  EXPECT_EQ (loaded->referenceFocalLength (), 210.f);
  EXPECT_EQ (loaded->serialize ("{\"note\": 1}"), readAll (path));
  BodyPartForest::Evaluation a, b;
  const ForestDepthImage img = stepImage ();
  ASSERT_TRUE (original.evaluate (img, allPixels (img), BodyPartForest::EvaluationOptions (), a));
  ASSERT_TRUE (loaded->evaluate (img, allPixels (img), BodyPartForest::EvaluationOptions (), b));
  EXPECT_EQ (a.labels, b.labels);
  EXPECT_EQ (a.probabilities, b.probabilities);

  const std::string bytes = readAll (path);
  auto refused = [&] (const std::string &content, const std::string &expect) {
    const std::string bad = dir.file ("bad.agexforest");
    writeAll (bad, content);
    const std::string m = modelError ([&] { BodyPartForest::load (bad); });
    EXPECT_NE (m.find (bad), std::string::npos) << m;
    EXPECT_NE (m.find (expect), std::string::npos) << m;
  };
  refused (bytes.substr (0, bytes.size () - 1), "truncated");
  refused (bytes.substr (0, 30), "truncated");
  refused (bytes + "x", "trailing");
  std::string flipped = bytes;
  flipped[bytes.size () / 2] = static_cast<char> (flipped[bytes.size () / 2] ^ 1);
  refused (flipped, "damaged");
  std::string version = bytes;
  version[8] = 2;
  refused (version, "version 2");
  // Magic present but nothing else: truncated, not a PCL file.
  refused (bytes.substr (0, 8), "truncated");
  // A reference focal length of 1 px, checksum intact: refused on load, naming the file and
  // the field (it once loaded, and then every frame was refused by evaluate ()).
  for (const float focal : {1.f, 9.f, 2e5f, std::numeric_limits<float>::infinity ()})
  {
    std::string tiny = bytes;
    const std::size_t at = 8 + 4 + 8 + 4 * 3 + 4;  // magic, version, size, C T rule, background
    std::memcpy (&tiny[at], &focal, 4);
    boost::crc_32_type crc;
    crc.process_bytes (tiny.data (), tiny.size () - 4);
    const std::uint32_t sum = crc.checksum ();
    for (int b = 0; b < 4; ++b)
      tiny[tiny.size () - 4 + b] = static_cast<char> ((sum >> (8 * b)) & 0xff);
    refused (tiny, "reference focal length");
  }
  EXPECT_THROW (BodyPartForest (fourClasses (), {twoLevelTree ()}, 1.f, BodyPartForest::VoteRule::Average, -1),
                agex::ModelError);
  EXPECT_NO_THROW (BodyPartForest (fourClasses (), {twoLevelTree ()}, 10.f, BodyPartForest::VoteRule::Average, -1));
  // A structurally invalid forest with a valid checksum is refused by the checks.
  {
    Tree bad = sparse;
    bad.children = {1, -1, -1};  // leaf 0 twice
    EXPECT_THROW (BodyPartForest (fourClasses (), {bad}, 525.f, BodyPartForest::VoteRule::Average, -1), agex::ModelError);
    bad.children = {0, -1, -2};  // a cycle
    EXPECT_THROW (BodyPartForest (fourClasses (), {bad}, 525.f, BodyPartForest::VoteRule::Average, -1), agex::ModelError);
    bad = sparse;
    bad.leaf_distributions[0] = std::numeric_limits<float>::quiet_NaN ();
    EXPECT_THROW (BodyPartForest (fourClasses (), {bad}, 525.f, BodyPartForest::VoteRule::Average, -1), agex::ModelError);
    bad = twoLevelTree ();
    bad.leaf_labels.pop_back ();
    EXPECT_THROW (BodyPartForest (fourClasses (), {bad}, 525.f, BodyPartForest::VoteRule::Average, -1), agex::ModelError);
  }
}

// --- the labelling stage and its point type ---------------------------------------------------

TEST (BodyPartLabeling, OutputCloudAndPcdRoundTrip)
{
  TempDir dir;
  const auto forest = std::make_shared<BodyPartForest> (fourClasses (), std::vector<Tree>{twoLevelTree ()}, 525.f,
                                                        BodyPartForest::VoteRule::PclMajority, -1);
  const auto cloud = syntheticPerson (64, 48, 1);
  pcl::Indices fg = finiteIndices (*cloud);
  const std::size_t given = fg.size () / 2;
  fg.resize (given);
  agex::BodyPartLabeling<pcl::PointXYZ> labeling;
  labeling.setInputCloud (cloud);
  labeling.setIndices (std::make_shared<pcl::Indices> (fg));
  labeling.setForest (forest);
  pcl::PointCloud<agex::BodyPartLabelPoint> labels;
  ASSERT_TRUE (labeling.compute (labels));
  ASSERT_EQ (labels.width, 64u);
  ASSERT_EQ (labels.height, 48u);
  std::size_t labelled = 0;
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    const auto &q = labels[i];
    if (q.label < 0)
    {
      EXPECT_TRUE (std::isnan (q.x) && std::isnan (q.p_head)) << i;
      continue;
    }
    ++labelled;
    EXPECT_EQ (q.z, (*cloud)[i].z);
    EXPECT_NEAR (q.p_head + q.p_hand + q.p_foot + q.p_other, 1.f, 1e-6f);
    EXPECT_EQ (q.probability (q.label), 1.f);  // one tree
  }
  EXPECT_EQ (labelled, given);

  const std::string path = dir.file ("labels.pcd");
  ASSERT_EQ (pcl::io::savePCDFileBinary (path, labels), 0);
  pcl::PointCloud<agex::BodyPartLabelPoint> back;
  ASSERT_EQ (pcl::io::loadPCDFile (path, back), 0);
  ASSERT_EQ (back.width, labels.width);
  ASSERT_EQ (back.height, labels.height);
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    EXPECT_EQ (back[i].label, labels[i].label);
    EXPECT_EQ (bits (back[i].x), bits (labels[i].x));
    EXPECT_EQ (bits (back[i].z), bits (labels[i].z));
    EXPECT_EQ (bits (back[i].p_hand), bits (labels[i].p_hand));
    EXPECT_EQ (bits (back[i].p_other), bits (labels[i].p_other));
  }
  // ASCII too (PCL writes NaN as nan).
  ASSERT_EQ (pcl::io::savePCDFileASCII (path, labels), 0);
  ASSERT_EQ (pcl::io::loadPCDFile (path, back), 0);
  for (std::size_t i = 0; i < labels.size (); ++i)
    EXPECT_EQ (back[i].label, labels[i].label);
  // pcl::PCLPointCloud2 sees the fields by name.
  pcl::PCLPointCloud2 blob;
  ASSERT_EQ (pcl::io::loadPCDFile (path, blob), 0);
  std::vector<std::string> names;
  for (const auto &f : blob.fields)
    names.push_back (f.name);
  EXPECT_EQ (names, (std::vector<std::string>{"x", "y", "z", "label", "p_head", "p_hand", "p_foot", "p_other"}));
}

TEST (BodyPartLabeling, BadInputIsRefusedOrEmpty)
{
  QuietPcl quiet;
  const auto forest = std::make_shared<BodyPartForest> (fourClasses (), std::vector<Tree>{twoLevelTree ()}, 525.f,
                                                        BodyPartForest::VoteRule::PclMajority, -1);
  agex::BodyPartLabeling<pcl::PointXYZ> labeling;
  pcl::PointCloud<agex::BodyPartLabelPoint> out;
  EXPECT_FALSE (labeling.compute (out));  // no input
  Cloud::Ptr unorganized (new Cloud);
  unorganized->push_back (pcl::PointXYZ (0, 0, 1));
  labeling.setInputCloud (unorganized);
  labeling.setForest (forest);
  EXPECT_FALSE (labeling.compute (out));
  EXPECT_TRUE (out.empty ());
  labeling.setInputCloud (nanCloud (32, 24));
  labeling.setForest (nullptr);
  EXPECT_FALSE (labeling.compute (out));
  labeling.setForest (std::make_shared<BodyPartForest> ());
  EXPECT_FALSE (labeling.compute (out));
  labeling.setForest (forest);
  labeling.setStride (0);
  EXPECT_FALSE (labeling.compute (out));
  labeling.setStride (1);
  labeling.setFocalLength (std::numeric_limits<float>::quiet_NaN ());
  EXPECT_FALSE (labeling.compute (out));
  labeling.setFocalLength (525.f * 100.f);
  EXPECT_FALSE (labeling.compute (out));
  labeling.setFocalLength (0.f);
  // All NaN, without indices (every pixel given): all unlabelled, no error.
  ASSERT_TRUE (labeling.compute (out));
  ASSERT_EQ (out.size (), 32u * 24u);
  for (const auto &q : out)
    EXPECT_EQ (q.label, agex::kLabelNone);
  // Empty and out-of-range indices.
  labeling.setIndices (std::make_shared<pcl::Indices> ());
  ASSERT_TRUE (labeling.compute (out));
  labeling.setIndices (std::make_shared<pcl::Indices> (pcl::Indices{-1, 5000, 3}));
  ASSERT_TRUE (labeling.compute (out));
  for (const auto &q : out)
    EXPECT_EQ (q.label, agex::kLabelNone);
  // An empty cloud (PCL calls it unorganized): refused, no crash.
  labeling.setInputCloud (Cloud::Ptr (new Cloud (0, 0)));
  labeling.setIndices (std::make_shared<pcl::Indices> ());
  EXPECT_FALSE (labeling.compute (out));
  EXPECT_TRUE (out.empty ());
}

// --- part modes --------------------------------------------------------------------------------

namespace
{
/** The modes of labels with the default parameters but the focal length f (pixels). */
bool
modesWithFocal (const pcl::PointCloud<agex::BodyPartLabelPoint> &labels, float f, agex::PartModeEstimation &estimation,
                agex::PartModeParams &params, std::vector<agex::PartMode> &modes)
{
  params.fx = params.fy = f;
  estimation.setParams (params);
  return estimation.compute (labels, modes);
}
}  // namespace

TEST (PartModeEstimation, TwoHandsWithTipsAndDirections)
{
  // A label cloud: a body column (other body) and two hand bars sticking out left and right
  // at depth 2 m; the tips are the bars' outer ends.
  pcl::PointCloud<agex::BodyPartLabelPoint> labels (80, 60);
  const float f = 100.f;  // pixels: 2 cm per pixel at 2 m
  for (int v = 0; v < 60; ++v)
    for (int u = 0; u < 80; ++u)
    {
      agex::BodyPartLabelPoint &q = labels (u, v);
      const bool body = u >= 35 && u < 45;
      const bool hand_l = v >= 28 && v < 32 && u >= 27 && u < 35;
      const bool hand_r = v >= 28 && v < 32 && u >= 45 && u < 52;
      if (!body && !hand_l && !hand_r)
        continue;
      q.z = 2.f;
      q.x = (u - 39.5f) * q.z / f;
      q.y = (v - 29.5f) * q.z / f;
      q.p_head = q.p_foot = 0.f;
      q.p_hand = body ? 0.f : 0.9f;
      q.p_other = body ? 1.f : 0.1f;
      q.label = body ? agex::kLabelOtherBody : agex::kLabelHand;
    }
  agex::PartModeEstimation estimation;
  agex::PartModeParams params;
  std::vector<agex::PartMode> modes;
  ASSERT_TRUE (modesWithFocal (labels, f, estimation, params, modes));
  ASSERT_EQ (modes.size (), 2u);
  for (const auto &m : modes)
  {
    EXPECT_EQ (m.part, agex::kLabelHand);
    EXPECT_GT (m.confidence, 0.f);
    EXPECT_LT (m.confidence, 1.f);
    EXPECT_NEAR (m.mean_probability, 0.9f, 1e-5f);
    const bool left = m.position.x () < 0.f;
    // Support: the whole bar (8 x 4 or 7 x 4 pixels), mass = 0.9 z^2 / f^2 per pixel.
    EXPECT_EQ (m.support.size (), left ? 32u : 28u);
    EXPECT_NEAR (m.mass, m.support.size () * 0.9f * 4.f / (f * f), 1e-5f);
    // Direction along the bar, away from the body; the tip at the bar's outer end.
    EXPECT_GT (std::abs (m.direction.x ()), 0.95f);
    EXPECT_EQ (m.direction.x () < 0.f, left);
    const int tip_u = m.tip_index % 80;
    EXPECT_EQ (tip_u, left ? 27 : 51);
  }
  // The longer bar has more mass: it comes first.
  EXPECT_LT (modes[0].position.x (), 0.f);
  // Nothing labelled: no modes; bad parameters: refused.
  pcl::PointCloud<agex::BodyPartLabelPoint> empty (10, 10);
  ASSERT_TRUE (estimation.compute (empty, modes));
  EXPECT_TRUE (modes.empty ());
  QuietPcl quiet;
  params.bandwidth[1] = 0.f;
  estimation.setParams (params);
  EXPECT_FALSE (estimation.compute (labels, modes));
}

// The mode must be a fixed point of the Gaussian mean shift the header documents (kernel
// exp (-d^2 / b^2), cut at 3 b), computed here in double precision with std::exp: this pins
// the estimator's fast kernel arithmetic to the real Gaussian. The density is lopsided (a
// heavy blob and a light one 4 cm apart, both within the kernel's reach), so a kernel of the
// wrong width or shape would settle elsewhere (blobs 4 cm apart at their edges, 10 cm between
// centres).
TEST (PartModeEstimation, ModeIsAFixedPointOfTheGaussianMeanShift)
{
  pcl::PointCloud<agex::BodyPartLabelPoint> labels (60, 40);
  const float f = 200.f;  // 1 cm per pixel at 2 m
  for (int v = 0; v < 40; ++v)
    for (int u = 0; u < 60; ++u)
    {
      const bool heavy = u >= 20 && u < 28 && v >= 16 && v < 24;
      const bool light = u >= 32 && u < 36 && v >= 18 && v < 22;
      if (!heavy && !light)
        continue;
      agex::BodyPartLabelPoint &q = labels (u, v);
      q.z = 2.f + 0.002f * static_cast<float> ((u * 7 + v * 3) % 5);  // a little relief
      q.x = (u - 30.f) * q.z / f;
      q.y = (v - 20.f) * q.z / f;
      q.p_head = heavy ? 0.9f : 0.5f;
      q.p_hand = q.p_foot = 0.f;
      q.p_other = 1.f - q.p_head;
      q.label = agex::kLabelHead;
    }
  agex::PartModeEstimation estimation;
  agex::PartModeParams params;
  std::vector<agex::PartMode> modes;
  ASSERT_TRUE (modesWithFocal (labels, f, estimation, params, modes));
  ASSERT_EQ (modes.size (), 1u);
  const Eigen::Vector3d x = modes[0].position.cast<double> ();
  const double b = params.bandwidth[agex::kLabelHead];
  Eigen::Vector3d num = Eigen::Vector3d::Zero ();
  double den = 0.0;
  for (const auto &q : labels)
  {
    if (q.label != agex::kLabelHead)
      continue;
    const Eigen::Vector3d p = q.getVector3fMap ().cast<double> ();
    const double d2 = (p - x).squaredNorm ();
    if (d2 > 9.0 * b * b)
      continue;
    const double k = q.p_head * q.z * q.z * std::exp (-d2 / (b * b));
    num += k * p;
    den += k;
  }
  ASSERT_GT (den, 0.0);
  const Eigen::Vector3d next = num / den;
  // The estimator sums cell means (atoms) rather than pixels, a quarter bandwidth wide: a few
  // hundredths of a millimetre here; a kernel 10% too wide or narrow moves it by 0.6 mm, 1.4
  // times too wide by 2 mm.
  EXPECT_LT ((next - x).norm (), 5e-4) << "mode " << x.transpose () << ", one step from it " << next.transpose ();
  // Between the blobs' centres, pulled towards the heavy one.
  EXPECT_GT (x.x (), -0.07);
  EXPECT_LT (x.x (), -0.01);
}

// pixel_step 2 (a forest pass at stride 2): only the pixels at even columns and rows are samples,
// each standing for 4 pixels. The modes must be those of the same cloud with every other pixel
// unlabelled, with 4 times the mass.
TEST (PartModeEstimation, PixelStepTakesEveryOtherRowAndColumn)
{
  pcl::PointCloud<agex::BodyPartLabelPoint> labels (81, 61), representatives (81, 61);
  const float f = 100.f;
  for (int v = 0; v < 61; ++v)
    for (int u = 0; u < 81; ++u)
    {
      agex::BodyPartLabelPoint q;
      const bool body = u >= 35 && u < 45;
      const bool hand_l = v >= 27 && v < 33 && u >= 25 && u < 35;
      const bool hand_r = v >= 27 && v < 32 && u >= 45 && u < 53;
      const bool foot = v >= 50 && v < 56 && u >= 36 && u < 47;
      if (!body && !hand_l && !hand_r && !foot)
        continue;
      q.z = 2.f + 0.002f * static_cast<float> (u % 7);
      q.x = (u - 40.f) * q.z / f;
      q.y = (v - 30.f) * q.z / f;
      q.p_head = 0.f;
      q.p_hand = hand_l || hand_r ? 0.8f : 0.f;
      q.p_foot = foot ? 0.7f : 0.f;
      q.p_other = 1.f - q.p_hand - q.p_foot;
      q.label = hand_l || hand_r ? agex::kLabelHand : foot ? agex::kLabelFoot : agex::kLabelOtherBody;
      labels (u, v) = q;
      if (u % 2 == 0 && v % 2 == 0)
        representatives (u, v) = q;
    }
  agex::PartModeEstimation estimation;
  agex::PartModeParams params;
  params.fx = params.fy = f;
  estimation.setParams (params);
  std::vector<agex::PartMode> expected, modes;
  ASSERT_TRUE (estimation.compute (representatives, expected));
  params.pixel_step = 2;
  estimation.setParams (params);
  ASSERT_TRUE (estimation.compute (labels, modes));
  ASSERT_EQ (modes.size (), 3u);  // two hands, one foot
  ASSERT_EQ (modes.size (), expected.size ());
  for (std::size_t i = 0; i < modes.size (); ++i)
  {
    EXPECT_EQ (modes[i].part, expected[i].part);
    EXPECT_TRUE (modes[i].position.isApprox (expected[i].position, 1e-6f));
    EXPECT_NEAR (modes[i].mass, 4.f * expected[i].mass, 1e-6f);
    EXPECT_EQ (modes[i].support, expected[i].support);
    EXPECT_EQ (modes[i].tip_index, expected[i].tip_index);
    EXPECT_TRUE (modes[i].direction.isApprox (expected[i].direction, 1e-5f));
    for (const auto index : modes[i].support)
      EXPECT_TRUE (index % 81 % 2 == 0 && index / 81 % 2 == 0) << "pixel " << index << " is not a representative";
  }
}

// Given the pixels that may be labelled (the labelling stage's, here shuffled, with some
// unlabelled ones and duplicates among them), the modes are those of the whole-frame scan, at
// pixel step 1 and 2; pixels that leave out a labelled bar leave out its mode.
TEST (PartModeEstimation, GivenPixelsGiveTheWholeFramesModes)
{
  pcl::PointCloud<agex::BodyPartLabelPoint> labels (81, 61);
  const float f = 100.f;
  pcl::Indices pixels, without_left_hand;
  for (int v = 0; v < 61; ++v)
    for (int u = 0; u < 81; ++u)
    {
      const int i = v * 81 + u;
      const bool body = u >= 35 && u < 45;
      const bool hand_l = v >= 27 && v < 33 && u >= 25 && u < 35;
      const bool hand_r = v >= 27 && v < 32 && u >= 45 && u < 53;
      if (u % 9 == 0 || body || hand_l || hand_r)
      {
        pixels.push_back (i);
        if (!hand_l)
          without_left_hand.push_back (i);
      }
      if (!body && !hand_l && !hand_r)
        continue;
      agex::BodyPartLabelPoint &q = labels (u, v);
      q.z = 2.f + 0.002f * static_cast<float> (u % 5);
      q.x = (u - 40.f) * q.z / f;
      q.y = (v - 30.f) * q.z / f;
      q.p_head = q.p_foot = 0.f;
      q.p_hand = body ? 0.f : 0.85f;
      q.p_other = 1.f - q.p_hand;
      q.label = body ? agex::kLabelOtherBody : agex::kLabelHand;
    }
  pixels.push_back (pixels[17]);
  pixels.push_back (-3);
  pixels.push_back (81 * 61);
  std::shuffle (pixels.begin (), pixels.end (), std::mt19937 (5));
  agex::PartModeEstimation estimation;
  agex::PartModeParams params;
  params.fx = params.fy = f;
  for (const int step : {1, 2})
  {
    params.pixel_step = step;
    estimation.setParams (params);
    std::vector<agex::PartMode> expected, modes;
    ASSERT_TRUE (estimation.compute (labels, expected));
    ASSERT_TRUE (estimation.compute (labels, pixels, modes));
    ASSERT_EQ (expected.size (), 2u) << "step " << step;
    ASSERT_EQ (modes.size (), expected.size ()) << "step " << step;
    for (std::size_t m = 0; m < modes.size (); ++m)
    {
      EXPECT_EQ (modes[m].position, expected[m].position) << "step " << step;
      EXPECT_EQ (modes[m].support, expected[m].support) << "step " << step;
      EXPECT_EQ (modes[m].tip_index, expected[m].tip_index) << "step " << step;
      EXPECT_EQ (modes[m].direction, expected[m].direction) << "step " << step;
      EXPECT_EQ (modes[m].mass, expected[m].mass) << "step " << step;
    }
    ASSERT_TRUE (estimation.compute (labels, without_left_hand, modes));
    ASSERT_EQ (modes.size (), 1u) << "step " << step;
    EXPECT_GT (modes[0].position.x (), 0.f);
  }
}

// --- training ----------------------------------------------------------------------------------

namespace
{
/** A sphere "head" (radius 0.12 m) above a box "torso" (0.4 x 0.6 m), both facing the camera at
  * a random distance and position: head pixels are class 0, torso pixels class 3. */
agex::BodyPartTrainingFrame
headAndTorso (std::mt19937 &rng)
{
  std::uniform_real_distribution<float> z0 (2.f, 3.5f), shift (-0.1f, 0.1f);
  const float z = z0 (rng), x0 = shift (rng), y0 = shift (rng);
  const int W = 120, H = 120;
  const float f = 150.f, cx = 59.5f, cy = 59.5f;
  Cloud::Ptr cloud (new Cloud (W, H, nanPoint ()));
  agex::BodyPartTrainingFrame frame;
  frame.fx = frame.fy = f;
  const Eigen::Vector3f head (x0, y0 - 0.45f, z);
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u)
    {
      const Eigen::Vector3f ray ((u - cx) / f, (v - cy) / f, 1.f);
      // Sphere: nearest intersection.
      const float b = ray.dot (head), c = head.squaredNorm () - 0.12f * 0.12f, a = ray.squaredNorm ();
      const float disc = b * b - a * c;
      float depth = std::numeric_limits<float>::infinity ();
      int cls = -2;
      if (disc >= 0.f)
      {
        depth = (b - std::sqrt (disc)) / a;
        cls = 0;
      }
      // Box front face at z + 0.05.
      const float zb = z + 0.05f;
      const float xb = ray.x () * zb, yb = ray.y () * zb;
      if (std::abs (xb - x0) < 0.2f && yb > y0 - 0.3f && yb < y0 + 0.3f && zb < depth)
      {
        depth = zb;
        cls = 3;
      }
      if (cls == -2)
        continue;
      (*cloud) (u, v) = pcl::PointXYZ (ray.x () * depth, ray.y () * depth, depth);
      frame.body.push_back (v * W + u);
      frame.classes.push_back (cls);
    }
  frame.cloud = cloud;
  return frame;
}
}  // namespace

TEST (BodyPartForestTrainer, SeparatesSphereHeadFromBoxTorso)
{
  std::mt19937 rng (42);
  std::vector<agex::BodyPartTrainingFrame> train, test;
  for (int i = 0; i < 20; ++i)
    train.push_back (headAndTorso (rng));
  for (int i = 0; i < 4; ++i)
    test.push_back (headAndTorso (rng));
  agex::BodyPartForestTrainerParams params;
  params.trees = 2;
  params.max_depth = 10;
  params.features_per_node = 100;
  params.thresholds_per_feature = 10;
  params.pixels_per_frame = 400;
  params.offset_range = 120;
  params.min_samples_per_leaf = 5;
  params.seed = 3;
  agex::BodyPartForestTrainer trainer;
  trainer.setParams (params);
  std::size_t progress_calls = 0, last_total = 0;
  const auto forest = trainer.train (train, [&] (std::size_t done, std::size_t total) {
    ++progress_calls;
    last_total = total;
    EXPECT_LE (done, total);
  });
  EXPECT_EQ (progress_calls, 2u * 11u);
  EXPECT_EQ (last_total, 22u);
  ASSERT_EQ (forest->trees ().size (), 2u);
  EXPECT_EQ (forest->numClasses (), 4);
  EXPECT_EQ (forest->classes ()[0].name, "head");
  EXPECT_GT (trainer.sampledPerClass ()[0], 0u);
  EXPECT_EQ (trainer.sampledPerClass ()[1], 0u);

  // Per-pixel accuracy on new frames, per class.
  std::array<std::size_t, 2> right{}, total{};
  for (const auto &frame : test)
  {
    agex::BodyPartLabeling<pcl::PointXYZ> labeling;
    labeling.setInputCloud (frame.cloud);
    labeling.setIndices (std::make_shared<pcl::Indices> (frame.body));
    labeling.setForest (forest);
    labeling.setFocalLength (frame.fx, frame.fy);
    pcl::PointCloud<agex::BodyPartLabelPoint> labels;
    ASSERT_TRUE (labeling.compute (labels));
    for (std::size_t j = 0; j < frame.body.size (); ++j)
    {
      const int k = frame.classes[j] == 0 ? 0 : 1;
      ++total[k];
      right[k] += labels[frame.body[j]].label == frame.classes[j] ? 1 : 0;
    }
  }
  EXPECT_GT (static_cast<double> (right[0]) / total[0], 0.95) << "head pixels";
  EXPECT_GT (static_cast<double> (right[1]) / total[1], 0.95) << "torso pixels";

  // Deterministic for a seed, whatever the threads; another seed gives another forest.
  params.threads = 2;
  trainer.setParams (params);
  const auto again = trainer.train (train);
  EXPECT_EQ (again->serialize (), forest->serialize ());
  params.seed = 4;
  trainer.setParams (params);
  EXPECT_NE (trainer.train (train)->serialize (), forest->serialize ());

  // Save/load round trip: identical outputs.
  TempDir dir;
  forest->save (dir.file ("f.bin"));
  const auto loaded = BodyPartForest::load (dir.file ("f.bin"));
  for (const auto &frame : test)
  {
    ForestDepthImage img;
    img.build (*frame.cloud, frame.body);
    BodyPartForest::EvaluationOptions o;
    o.fx = o.fy = frame.fx;
    BodyPartForest::Evaluation a, b;
    ASSERT_TRUE (forest->evaluate (img, frame.body, o, a));
    ASSERT_TRUE (loaded->evaluate (img, frame.body, o, b));
    EXPECT_EQ (a.labels, b.labels);
    EXPECT_EQ (a.probabilities, b.probabilities);
  }
}

TEST (BodyPartForestTrainer, BadParametersAndFrames)
{
  agex::BodyPartForestTrainer trainer;
  std::mt19937 rng (1);
  std::vector<agex::BodyPartTrainingFrame> frames{headAndTorso (rng)};
  agex::BodyPartForestTrainerParams p;
  p.max_depth = 25;
  trainer.setParams (p);
  EXPECT_THROW (trainer.train (frames), std::invalid_argument);
  p = agex::BodyPartForestTrainerParams ();
  p.offset_range = 0;
  trainer.setParams (p);
  EXPECT_THROW (trainer.train (frames), std::invalid_argument);
  trainer.setParams (agex::BodyPartForestTrainerParams ());
  auto bad = frames;
  bad[0].classes.pop_back ();
  EXPECT_THROW (trainer.train (bad), std::invalid_argument);
  bad = frames;
  bad[0].classes[0] = 7;
  EXPECT_THROW (trainer.train (bad), std::invalid_argument);
  bad = frames;
  bad[0].cloud = nullptr;
  EXPECT_THROW (trainer.train (bad), std::invalid_argument);
  bad = frames;
  std::fill (bad[0].classes.begin (), bad[0].classes.end (), -1);
  EXPECT_THROW (trainer.train (bad), std::runtime_error);
  EXPECT_THROW (trainer.train ({}), std::runtime_error);
}

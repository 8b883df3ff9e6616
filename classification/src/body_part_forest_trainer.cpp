// agex::BodyPartForestTrainer: greedy information-gain trees over depth-comparison features.

#include <agex/classification/body_part_forest_trainer.h>
#include <agex/classification/body_part_label_point.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>
#include <thread>

namespace agex
{
namespace
{
std::uint64_t
splitmix (std::uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

struct Sample
{
  std::int32_t frame;
  std::int32_t u, v;
  float su, sv;
  std::int32_t cls;
};

struct Split
{
  bool leaf = true;
  BodyPartForest::Node node;
  double gain = 0.0;
  std::size_t mid = 0;  ///< samples [begin, mid) go left
};

double
entropy (const double *h, int C, double total)
{
  if (!(total > 0.0))
    return 0.0;
  double e = 0.0;
  for (int c = 0; c < C; ++c)
    if (h[c] > 0.0)
    {
      const double p = h[c] / total;
      e -= p * std::log2 (p);
    }
  return e;
}

/** Runs fn (i) for i in [0, n) on up to threads threads (work taken in order). */
template <typename Fn>
void
parallelIndex (std::size_t n, int threads, Fn fn)
{
  const int t = static_cast<int> (std::min<std::size_t> (static_cast<std::size_t> (std::max (1, threads)), n));
  if (t <= 1)
  {
    for (std::size_t i = 0; i < n; ++i)
      fn (i, 0);
    return;
  }
  std::atomic<std::size_t> next (0);
  std::vector<std::thread> pool;
  auto work = [&] (int id) {
    for (std::size_t i; (i = next++) < n;)
      fn (i, id);
  };
  for (int i = 1; i < t; ++i)
    pool.emplace_back (work, i);
  work (0);
  for (auto &th : pool)
    th.join ();
}

class TreeBuilder
{
public:
  TreeBuilder (const BodyPartForestTrainerParams &p, int C, const std::vector<ForestDepthImage> &images,
               std::vector<Sample> &samples, const std::vector<double> &weights, std::uint64_t tree_seed)
    : P (p), C (C), images_ (images), samples_ (samples), weights_ (weights), seed_ (tree_seed)
  {
  }

  /** Histogram (weighted) and counts of samples [b, e). */
  void histogram (std::size_t b, std::size_t e, std::vector<double> &h) const
  {
    h.assign (C, 0.0);
    for (std::size_t i = b; i < e; ++i)
      h[samples_[i].cls] += weights_[samples_[i].cls];
  }

  int feature (const Sample &s, const BodyPartForest::Node &n) const
  {
    return forestFeature (images_[s.frame], s.u, s.v, s.su, s.sv, n);
  }

  /** The best split of [b, e) among features [f0, f1) of the candidate list. */
  Split bestSplit (std::size_t b, std::size_t e, const std::vector<BodyPartForest::Node> &features, std::size_t f0,
                   std::size_t f1, const std::vector<std::vector<std::size_t>> &picks, const std::vector<double> &parent,
                   double parent_total) const
  {
    Split best;
    best.gain = -1.0;
    const std::size_t n = e - b;
    std::vector<int> values (n);
    std::vector<float> thresholds;
    const int K = P.thresholds_per_feature;
    std::vector<double> bins ((K + 1) * static_cast<std::size_t> (C));
    std::vector<std::size_t> counts (K + 1);
    std::vector<double> left (C);
    const double parent_entropy = entropy (parent.data (), C, parent_total);
    for (std::size_t f = f0; f < f1; ++f)
    {
      for (std::size_t i = 0; i < n; ++i)
        values[i] = feature (samples_[b + i], features[f]);
      thresholds.clear ();
      for (const std::size_t pick : picks[f])
        thresholds.push_back (static_cast<float> (values[pick]) - 0.5f);
      std::sort (thresholds.begin (), thresholds.end ());
      thresholds.erase (std::unique (thresholds.begin (), thresholds.end ()), thresholds.end ());
      const std::size_t k = thresholds.size ();
      std::fill (bins.begin (), bins.begin () + (k + 1) * C, 0.0);
      std::fill (counts.begin (), counts.begin () + (k + 1), 0);
      for (std::size_t i = 0; i < n; ++i)
      {
        // m = thresholds below the value: the sample goes right for thresholds 0..m-1.
        const std::size_t m = static_cast<std::size_t> (
          std::lower_bound (thresholds.begin (), thresholds.end (), static_cast<float> (values[i])) - thresholds.begin ());
        const int c = samples_[b + i].cls;
        bins[m * C + c] += weights_[c];
        ++counts[m];
      }
      std::fill (left.begin (), left.end (), 0.0);
      std::size_t left_count = 0;
      for (std::size_t t = 0; t < k; ++t)
      {
        // Threshold t: samples of bins 0..t (values below it) go left.
        double lt = 0.0;
        for (int c = 0; c < C; ++c)
        {
          left[c] += bins[t * C + c];
          lt += left[c];
        }
        left_count += counts[t];
        const std::size_t right_count = n - left_count;
        if (left_count < static_cast<std::size_t> (P.min_samples_per_leaf) ||
            right_count < static_cast<std::size_t> (P.min_samples_per_leaf))
          continue;
        double right[256];
        double rt = 0.0;
        for (int c = 0; c < C; ++c)
        {
          right[c] = parent[c] - left[c];
          if (right[c] < 0.0)
            right[c] = 0.0;
          rt += right[c];
        }
        const double total = lt + rt;
        if (!(total > 0.0))
          continue;
        const double gain =
          parent_entropy - (lt / total) * entropy (left.data (), C, lt) - (rt / total) * entropy (right, C, rt);
        if (gain > best.gain)
        {
          best.gain = gain;
          best.node = features[f];
          best.node.threshold = thresholds[t];
          best.leaf = false;
        }
      }
    }
    return best;
  }

  /** Decides node [b, e) at level: a leaf, or the best split (samples partitioned). */
  Split decide (std::size_t b, std::size_t e, int level, int slot, int inner_threads) const
  {
    Split result;
    std::vector<double> h;
    histogram (b, e, h);
    const double total = std::accumulate (h.begin (), h.end (), 0.0);
    const int present = static_cast<int> (std::count_if (h.begin (), h.end (), [] (double x) { return x > 0.0; }));
    const std::size_t n = e - b;
    if (level >= P.max_depth || present <= 1 || n < 2 * static_cast<std::size_t> (P.min_samples_per_leaf))
      return result;

    std::mt19937_64 rng (splitmix (seed_ ^ splitmix (static_cast<std::uint64_t> (slot) + 1)));
    std::uniform_int_distribution<int> offset (-P.offset_range, P.offset_range);
    std::uniform_real_distribution<float> unit (0.f, 1.f);
    std::uniform_int_distribution<std::size_t> pick (0, n - 1);
    std::vector<BodyPartForest::Node> features (static_cast<std::size_t> (P.features_per_node));
    std::vector<std::vector<std::size_t>> picks (features.size ());
    for (std::size_t f = 0; f < features.size (); ++f)
    {
      auto &node = features[f];
      node.du1 = static_cast<std::int16_t> (offset (rng));
      node.dv1 = static_cast<std::int16_t> (offset (rng));
      if (unit (rng) < P.unary_probability)
        node.du2 = node.dv2 = 0;
      else
      {
        node.du2 = static_cast<std::int16_t> (offset (rng));
        node.dv2 = static_cast<std::int16_t> (offset (rng));
      }
      picks[f].resize (static_cast<std::size_t> (P.thresholds_per_feature));
      for (auto &p : picks[f])
        p = pick (rng);
    }

    Split best;
    best.gain = -1.0;
    if (inner_threads <= 1)
      best = bestSplit (b, e, features, 0, features.size (), picks, h, total);
    else
    {
      // Contiguous feature ranges per thread; the first best in feature order wins.
      const std::size_t parts = static_cast<std::size_t> (inner_threads);
      std::vector<Split> partial (parts);
      const std::size_t chunk = (features.size () + parts - 1) / parts;
      parallelIndex (parts, inner_threads, [&] (std::size_t i, int) {
        const std::size_t f0 = std::min (features.size (), i * chunk), f1 = std::min (features.size (), f0 + chunk);
        partial[i] = bestSplit (b, e, features, f0, f1, picks, h, total);
        if (f0 == f1)
          partial[i].gain = -1.0;
      });
      for (const auto &s : partial)
        if (!s.leaf && s.gain > best.gain)
          best = s;
    }
    if (best.leaf || best.gain < P.min_gain)
      return result;
    const auto it = std::partition (samples_.begin () + static_cast<std::ptrdiff_t> (b),
                                    samples_.begin () + static_cast<std::ptrdiff_t> (e), [&] (const Sample &s) {
                                      return !(static_cast<float> (feature (s, best.node)) > best.node.threshold);
                                    });
    best.mid = static_cast<std::size_t> (it - samples_.begin ());
    return best;
  }

  BodyPartForest::Tree build (const std::function<void ()> &level_done)
  {
    struct Work
    {
      std::size_t b, e;
      int slot, level;
    };
    BodyPartForest::Tree tree;
    tree.complete = false;
    tree.nodes.resize (1);
    tree.children.assign (1, 0);
    std::vector<Work> frontier{{0, samples_.size (), 0, 0}};
    int levels = 0;
    while (!frontier.empty ())
    {
      std::vector<Split> decisions (frontier.size ());
      // Big nodes one at a time over all threads, the rest one node per thread.
      std::vector<std::size_t> big, small;
      for (std::size_t i = 0; i < frontier.size (); ++i)
        (frontier[i].e - frontier[i].b >= 20000 && P.threads > 1 ? big : small).push_back (i);
      for (const std::size_t i : big)
        decisions[i] = decide (frontier[i].b, frontier[i].e, frontier[i].level, frontier[i].slot, P.threads);
      parallelIndex (small.size (), P.threads, [&] (std::size_t j, int) {
        const std::size_t i = small[j];
        decisions[i] = decide (frontier[i].b, frontier[i].e, frontier[i].level, frontier[i].slot, 1);
      });
      std::vector<Work> next;
      for (std::size_t i = 0; i < frontier.size (); ++i)
      {
        const Work &w = frontier[i];
        const Split &s = decisions[i];
        if (!s.leaf)
        {
          const int c = static_cast<int> (tree.nodes.size ());
          tree.nodes.resize (tree.nodes.size () + 2);
          tree.children.resize (tree.nodes.size (), 0);
          tree.nodes[w.slot] = s.node;
          tree.children[w.slot] = c;
          tree.depth = std::max (tree.depth, w.level + 1);
          next.push_back ({w.b, s.mid, c, w.level + 1});
          next.push_back ({s.mid, w.e, c + 1, w.level + 1});
          continue;
        }
        std::vector<double> h;
        histogram (w.b, w.e, h);
        const double total = std::accumulate (h.begin (), h.end (), 0.0);
        const int leaf = static_cast<int> (tree.leaf_labels.size ());
        tree.children[w.slot] = -(leaf + 1);
        tree.nodes[w.slot] = BodyPartForest::Node ();
        int arg = 0;
        for (int c = 0; c < C; ++c)
        {
          const float p = total > 0.0 ? static_cast<float> (h[c] / total) : 1.f / static_cast<float> (C);
          tree.leaf_distributions.push_back (p);
          if (h[c] > h[arg])
            arg = c;
        }
        tree.leaf_labels.push_back (static_cast<std::uint8_t> (arg));
      }
      frontier.swap (next);
      ++levels;
      if (level_done && levels <= P.max_depth + 1)
        level_done ();
    }
    for (; levels <= P.max_depth; ++levels)
      if (level_done)
        level_done ();
    return tree;
  }

private:
  const BodyPartForestTrainerParams &P;
  const int C;
  const std::vector<ForestDepthImage> &images_;
  std::vector<Sample> &samples_;
  const std::vector<double> &weights_;
  const std::uint64_t seed_;
};
}  // namespace

BodyPartForestTrainer::BodyPartForestTrainer ()
{
  for (int p = 0; p < kLabelPartCount; ++p)
    classes_.push_back ({labelPartName (p), p});
}

BodyPartForest::Ptr
BodyPartForestTrainer::train (const std::vector<BodyPartTrainingFrame> &frames, const Progress &progress) const
{
  const BodyPartForestTrainerParams &P = params_;
  const int C = static_cast<int> (classes_.size ());
  if (C < 1 || C > BodyPartForest::kMaxClasses)
    throw std::invalid_argument ("the trainer needs 1 to 255 classes");
  if (P.trees < 1 || P.trees > BodyPartForest::kMaxTrees || P.max_depth < 0 || P.max_depth > BodyPartForest::kMaxDepth ||
      P.features_per_node < 1 || P.thresholds_per_feature < 1 || P.pixels_per_frame < 1 || P.offset_range < 1 ||
      P.offset_range > 32767 || P.min_samples_per_leaf < 1 || P.threads < 1 || !(P.reference_focal >= BodyPartForest::kMinReferenceFocal) ||
      !(P.reference_focal <= BodyPartForest::kMaxReferenceFocal) || !(P.unary_probability >= 0.f && P.unary_probability <= 1.f) ||
      !std::isfinite (P.min_gain) || P.foreground_dilation < 0)
    throw std::invalid_argument ("forest trainer parameters out of range: trees 1-64, depth 0-24, features, "
                                 "thresholds, pixels per frame, min samples per leaf and threads at least 1, offset "
                                 "range 1-32767, a reference focal length of 10 to 100000 px, unary probability in [0, 1]");

  std::vector<ForestDepthImage> images (frames.size ());
  std::vector<std::vector<Sample>> candidates (frames.size ());
  for (std::size_t f = 0; f < frames.size (); ++f)
  {
    const auto &frame = frames[f];
    const std::string name = "training frame " + std::to_string (f);
    if (!frame.cloud || !frame.cloud->isOrganized ())
      throw std::invalid_argument (name + ": no organized cloud");
    if (frame.classes.size () != frame.body.size ())
      throw std::invalid_argument (name + ": " + std::to_string (frame.classes.size ()) + " classes for " +
                                   std::to_string (frame.body.size ()) + " body pixels");
    const double rx = frame.fx / P.reference_focal, ry = frame.fy / P.reference_focal;
    if (!std::isfinite (frame.fx) || !std::isfinite (frame.fy) || !(rx > 0.0 && rx <= 50.0) || !(ry > 0.0 && ry <= 50.0))
      throw std::invalid_argument (name + ": focal lengths not finite and positive, or over 50 times the reference");
    images[f].build (*frame.cloud, frame.body, P.foreground_dilation);
    const float Fu = static_cast<float> (BodyPartForest::kFeatureScale * rx);
    const float Fv = static_cast<float> (BodyPartForest::kFeatureScale * ry);
    const long long n = static_cast<long long> (frame.cloud->size ());
    const int w = static_cast<int> (frame.cloud->width);
    for (std::size_t i = 0; i < frame.body.size (); ++i)
    {
      const int cls = frame.classes[i];
      if (cls < -1 || cls >= C)
        throw std::invalid_argument (name + ": class " + std::to_string (cls) + " out of range");
      const auto idx = frame.body[i];
      if (cls < 0 || idx < 0 || idx >= n)
        continue;
      const int u = static_cast<int> (idx % w), v = static_cast<int> (idx / w);
      const std::uint16_t d = images[f].at (u, v);
      if (d == ForestDepthImage::kNoData || d == ForestDepthImage::kBackground)
        continue;
      Sample s;
      s.frame = static_cast<std::int32_t> (f);
      s.u = u;
      s.v = v;
      BodyPartForest::scales (Fu, Fv, d, s.su, s.sv);
      s.cls = cls;
      candidates[f].push_back (s);
    }
  }
  std::size_t available = 0;
  for (const auto &c : candidates)
    available += c.size ();
  if (available == 0)
    throw std::runtime_error ("no training frame has a labelled body pixel with depth");

  sampled_.assign (C, 0);
  std::vector<BodyPartForest::Tree> trees;
  const std::size_t total_levels = static_cast<std::size_t> (P.trees) * (P.max_depth + 1);
  std::size_t done = 0;
  for (int t = 0; t < P.trees; ++t)
  {
    const std::uint64_t tree_seed = splitmix (P.seed ^ splitmix (0x7265657274ull + static_cast<std::uint64_t> (t)));
    std::mt19937_64 rng (tree_seed);
    std::vector<Sample> samples;
    std::vector<Sample> scratch;
    for (const auto &c : candidates)
    {
      scratch = c;
      const std::size_t k = std::min (scratch.size (), static_cast<std::size_t> (P.pixels_per_frame));
      for (std::size_t i = 0; i < k; ++i)  // partial Fisher-Yates: k of them, uniformly
      {
        std::uniform_int_distribution<std::size_t> pick (i, scratch.size () - 1);
        std::swap (scratch[i], scratch[pick (rng)]);
      }
      samples.insert (samples.end (), scratch.begin (), scratch.begin () + static_cast<std::ptrdiff_t> (k));
    }
    std::vector<std::size_t> counts (C, 0);
    for (const auto &s : samples)
      ++counts[s.cls];
    const int present = static_cast<int> (std::count_if (counts.begin (), counts.end (), [] (std::size_t x) { return x > 0; }));
    std::vector<double> weights (C, 1.0);
    if (P.balance_classes)
      for (int c = 0; c < C; ++c)
        weights[c] = counts[c] ? static_cast<double> (samples.size ()) / (present * static_cast<double> (counts[c])) : 0.0;
    for (int c = 0; c < C; ++c)
      sampled_[c] += counts[c];
    TreeBuilder builder (P, C, images, samples, weights, tree_seed);
    trees.push_back (builder.build ([&] () {
      ++done;
      if (progress)
        progress (done, total_levels);
    }));
  }
  return std::make_shared<BodyPartForest> (classes_, std::move (trees), P.reference_focal,
                                           BodyPartForest::VoteRule::Average, -1);
}
}  // namespace agex

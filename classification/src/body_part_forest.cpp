// agex::BodyPartForest: checks, evaluation (the trees, the vote, PCL's tie-break and
// smoothing) and our binary model file. PCL's text tree files: pcl_tree_reader.cpp.

#include <agex/classification/body_part_forest.h>
#include <agex/classification/body_part_label_point.h>
#include <agex/io/atomic_file.h>

#include <pcl/console/print.h>

#include <boost/crc.hpp>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <thread>

namespace agex
{
const char *
labelPartName (int part)
{
  switch (part)
  {
  case kLabelHead: return "head";
  case kLabelHand: return "hand";
  case kLabelFoot: return "foot";
  case kLabelOtherBody: return "other_body";
  default: return "none";
  }
}

bool
parseLabelPart (const char *name, int &part)
{
  for (int p = -1; p < kLabelPartCount; ++p)
    if (std::strcmp (name, labelPartName (p)) == 0)
    {
      part = p;
      return true;
    }
  return false;
}

void
ForestDepthImage::reset (int frame_width, int frame_height, int x0, int y0, int width, int height)
{
  frame_width_ = std::max (0, frame_width);
  frame_height_ = std::max (0, frame_height);
  const int xa = std::clamp (x0, 0, frame_width_), ya = std::clamp (y0, 0, frame_height_);
  const long long xb = std::clamp<long long> (static_cast<long long> (x0) + std::max (0, width), 0, frame_width_);
  const long long yb = std::clamp<long long> (static_cast<long long> (y0) + std::max (0, height), 0, frame_height_);
  x0_ = xa;
  y0_ = ya;
  width_ = static_cast<int> (std::max<long long> (0, xb - xa));
  height_ = static_cast<int> (std::max<long long> (0, yb - ya));
  if (width_ == 0 || height_ == 0)
    width_ = height_ = 0;
  data_.assign (static_cast<std::size_t> (width_) * height_, kBackground);
}

namespace
{
constexpr char kMagic[8] = {'A', 'G', 'E', 'X', 'F', 'R', 'S', 'T'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::size_t kMaxNameLength = 64;
constexpr std::size_t kMaxMetadata = std::size_t (16) << 20;
constexpr std::uint64_t kMaxFileBytes = std::uint64_t (2) << 30;
/** Slots of a trained (sparse) tree: far more than any training set gives. */
constexpr std::uint32_t kMaxSparseSlots = std::uint32_t (1) << 25;

/** Runs fn (begin, end) over [0, n) on up to threads threads in contiguous chunks. */
void
parallelFor (std::size_t n, int threads, const std::function<void (std::size_t, std::size_t)> &fn)
{
  const std::size_t t = std::max<std::size_t> (1, std::min<std::size_t> (threads < 1 ? 1 : threads, n / 256 + 1));
  if (t <= 1)
  {
    fn (0, n);
    return;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (n + t - 1) / t;
  for (std::size_t i = 1; i < t; ++i)
  {
    const std::size_t b = std::min (n, i * chunk), e = std::min (n, b + chunk);
    if (b < e)
      pool.emplace_back (fn, b, e);
  }
  fn (0, std::min (n, chunk));
  for (auto &th : pool)
    th.join ();
}

template <bool Complete>
inline int
descend (const BodyPartForest::Tree &tree, const ForestDepthImage &depth, int u, int v, float su, float sv)
{
  if (Complete)
  {
    const BodyPartForest::Node *nodes = tree.nodes.data ();
    int n = 0;
    for (int level = 0; level < tree.depth; ++level)
    {
      const BodyPartForest::Node &node = nodes[n];
      const bool right = static_cast<float> (forestFeature (depth, u, v, su, sv, node)) > node.threshold;
      n = 2 * n + 1 + (right ? 1 : 0);
    }
    return n - static_cast<int> (tree.nodes.size ());
  }
  const std::int32_t *children = tree.children.data ();
  int n = 0;
  while (children[n] >= 0)
  {
    const BodyPartForest::Node &node = tree.nodes[n];
    const bool right = static_cast<float> (forestFeature (depth, u, v, su, sv, node)) > node.threshold;
    n = children[n] + (right ? 1 : 0);
  }
  return -children[n] - 1;
}

inline int
descendTree (const BodyPartForest::Tree &tree, const ForestDepthImage &depth, int u, int v, float su, float sv)
{
  return tree.complete ? descend<true> (tree, depth, u, v, su, sv) : descend<false> (tree, depth, u, v, su, sv);
}

/** Pixels run through a tree together, level by level, so that their node fetches (cache
  * misses deep in a 12 MB tree) overlap instead of waiting one after the other. */
constexpr int kBatch = 32;

/** Leaves of n <= kBatch pixels in one tree; the same leaves as descendTree, faster. */
inline void
descendBatch (const BodyPartForest::Tree &tree, const ForestDepthImage &depth, const int *u, const int *v,
              const float *su, const float *sv, int n, int *leaf)
{
  const BodyPartForest::Node *nodes = tree.nodes.data ();
  int at[kBatch];
  for (int i = 0; i < n; ++i)
    at[i] = 0;
  if (tree.complete)
  {
    const int last = tree.depth - 1;
    for (int level = 0; level <= last; ++level)
      for (int i = 0; i < n; ++i)
      {
        const BodyPartForest::Node &node = nodes[at[i]];
        const bool right = static_cast<float> (forestFeature (depth, u[i], v[i], su[i], sv[i], node)) > node.threshold;
        at[i] = 2 * at[i] + 1 + (right ? 1 : 0);
        if (level < last)
          __builtin_prefetch (nodes + at[i]);
      }
    const int internal = static_cast<int> (tree.nodes.size ());
    for (int i = 0; i < n; ++i)
      leaf[i] = at[i] - internal;
    return;
  }
  const std::int32_t *children = tree.children.data ();
  for (int level = 0; level < tree.depth; ++level)
  {
    bool any = false;
    for (int i = 0; i < n; ++i)
    {
      const std::int32_t c = children[at[i]];
      if (c < 0)
        continue;
      const BodyPartForest::Node &node = nodes[at[i]];
      const bool right = static_cast<float> (forestFeature (depth, u[i], v[i], su[i], sv[i], node)) > node.threshold;
      at[i] = c + (right ? 1 : 0);
      __builtin_prefetch (nodes + at[i]);
      any = true;
    }
    if (!any)
      break;
  }
  for (int i = 0; i < n; ++i)
    leaf[i] = -children[at[i]] - 1;
}

// The same descent with the probes computed by FMA and SSE4.1 instructions: the four probe
// coordinates of a node in one fused multiply-add (exactly PCL's GPU arithmetic, which the
// generic path above emulates in double), truncated, offset and clamped together. Picked at
// run time on processors that have them; the leaves are the same.
}  // namespace
}  // namespace agex
#include <immintrin.h>
namespace agex
{
namespace
{
// A function attribute, not #pragma GCC target: clang ignores the pragma, and a lambda does
// not inherit its enclosing function's target, so the intrinsics live in fmaStep.
#define AGEX_TARGET_AVX2_FMA __attribute__ ((target ("avx2,fma")))

struct FmaProbe
{
  __m128i origin, top, row, zero;
  const std::uint16_t *img;
};

AGEX_TARGET_AVX2_FMA inline bool
fmaStep (const FmaProbe &p, __m128 scale, __m128 base, const BodyPartForest::Node &node)
{
  const __m128i off16 = _mm_loadl_epi64 (reinterpret_cast<const __m128i *> (&node));
  const __m128 off = _mm_cvtepi32_ps (_mm_cvtepi16_epi32 (off16));
  __m128i c = _mm_cvttps_epi32 (_mm_fmadd_ps (off, scale, base));
  c = _mm_min_epi32 (_mm_max_epi32 (_mm_sub_epi32 (c, p.origin), p.zero), p.top);
  const __m128i idx = _mm_hadd_epi32 (_mm_mullo_epi32 (c, p.row), p.zero);
  const int d1 = p.img[_mm_cvtsi128_si32 (idx)];
  const int d2 = p.img[_mm_extract_epi32 (idx, 1)];
  return static_cast<float> (d1 - d2) > node.threshold;
}

AGEX_TARGET_AVX2_FMA void
descendBatchFma (const BodyPartForest::Tree &tree, const ForestDepthImage &depth, const int *u, const int *v,
                 const float *su, const float *sv, int n, int *leaf)
{
  static_assert (sizeof (BodyPartForest::Node) == 12 && offsetof (BodyPartForest::Node, threshold) == 8,
                 "the kernel loads a node's four offsets as one 64-bit word");
  const BodyPartForest::Node *nodes = tree.nodes.data ();
  const std::uint16_t *img = depth.data ();
  const int W = depth.width ();
  const __m128i origin = _mm_setr_epi32 (depth.x0 (), depth.y0 (), depth.x0 (), depth.y0 ());
  const __m128i top = _mm_setr_epi32 (W - 1, depth.height () - 1, W - 1, depth.height () - 1);
  const __m128i row = _mm_setr_epi32 (1, W, 1, W);
  const __m128i zero = _mm_setzero_si128 ();
  __m128 scale[kBatch], base[kBatch];
  int at[kBatch];
  for (int i = 0; i < n; ++i)
  {
    scale[i] = _mm_setr_ps (su[i], sv[i], su[i], sv[i]);
    base[i] = _mm_setr_ps (static_cast<float> (u[i]), static_cast<float> (v[i]), static_cast<float> (u[i]),
                           static_cast<float> (v[i]));
    at[i] = 0;
  }
  const FmaProbe probe{origin, top, row, zero, img};
  auto step = [&] (int i, const BodyPartForest::Node &node) { return fmaStep (probe, scale[i], base[i], node); };
  if (tree.complete)
  {
    const int last = tree.depth - 1;
    for (int level = 0; level <= last; ++level)
      for (int i = 0; i < n; ++i)
      {
        at[i] = 2 * at[i] + 1 + (step (i, nodes[at[i]]) ? 1 : 0);
        if (level < last)
          _mm_prefetch (reinterpret_cast<const char *> (nodes + at[i]), _MM_HINT_T0);
      }
    const int internal = static_cast<int> (tree.nodes.size ());
    for (int i = 0; i < n; ++i)
      leaf[i] = at[i] - internal;
    return;
  }
  const std::int32_t *children = tree.children.data ();
  for (int level = 0; level < tree.depth; ++level)
  {
    bool any = false;
    for (int i = 0; i < n; ++i)
    {
      const std::int32_t c = children[at[i]];
      if (c < 0)
        continue;
      at[i] = c + (step (i, nodes[at[i]]) ? 1 : 0);
      _mm_prefetch (reinterpret_cast<const char *> (nodes + at[i]), _MM_HINT_T0);
      any = true;
    }
    if (!any)
      break;
  }
  for (int i = 0; i < n; ++i)
    leaf[i] = -children[at[i]] - 1;
}

bool
haveFma ()
{
  static const bool have = __builtin_cpu_supports ("avx2") && __builtin_cpu_supports ("fma");
  return have;
}

// --- little-endian byte I/O ---------------------------------------------------------------

class Writer
{
public:
  void bytes (const void *p, std::size_t n) { out_.append (static_cast<const char *> (p), n); }
  void u8 (std::uint8_t v) { out_.push_back (static_cast<char> (v)); }
  void u32 (std::uint32_t v)
  {
    for (int i = 0; i < 4; ++i)
      u8 (static_cast<std::uint8_t> (v >> (8 * i)));
  }
  void u64 (std::uint64_t v)
  {
    for (int i = 0; i < 8; ++i)
      u8 (static_cast<std::uint8_t> (v >> (8 * i)));
  }
  void i32 (std::int32_t v) { u32 (static_cast<std::uint32_t> (v)); }
  void i16 (std::int16_t v)
  {
    const auto u = static_cast<std::uint16_t> (v);
    u8 (static_cast<std::uint8_t> (u));
    u8 (static_cast<std::uint8_t> (u >> 8));
  }
  void f32 (float v)
  {
    std::uint32_t b;
    std::memcpy (&b, &v, 4);
    u32 (b);
  }
  void str (const std::string &s)
  {
    u32 (static_cast<std::uint32_t> (s.size ()));
    bytes (s.data (), s.size ());
  }
  std::string &buffer () { return out_; }

private:
  std::string out_;
};

class Reader
{
public:
  Reader (const std::string &bytes, const std::string &name) : b_ (bytes), name_ (name) {}
  [[noreturn]] void fail (const std::string &what) const
  {
    throw ModelError (name_ + ": " + what + " (at byte " + std::to_string (pos_) + ")");
  }
  void need (std::uint64_t n, const char *what) const
  {
    if (n > b_.size () - pos_)
      fail (std::string ("truncated: ") + what + " needs " + std::to_string (n) + " bytes, " +
            std::to_string (b_.size () - pos_) + " left");
  }
  std::uint8_t u8 ()
  {
    need (1, "a byte");
    return static_cast<std::uint8_t> (b_[pos_++]);
  }
  std::uint32_t u32 ()
  {
    need (4, "a 32-bit field");
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
      v |= static_cast<std::uint32_t> (static_cast<std::uint8_t> (b_[pos_ + i])) << (8 * i);
    pos_ += 4;
    return v;
  }
  std::uint64_t u64 ()
  {
    need (8, "a 64-bit field");
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i)
      v |= static_cast<std::uint64_t> (static_cast<std::uint8_t> (b_[pos_ + i])) << (8 * i);
    pos_ += 8;
    return v;
  }
  std::int32_t i32 () { return static_cast<std::int32_t> (u32 ()); }
  std::int16_t i16 ()
  {
    need (2, "a 16-bit field");
    const auto v = static_cast<std::uint16_t> (static_cast<std::uint8_t> (b_[pos_]) |
                                               (static_cast<std::uint16_t> (static_cast<std::uint8_t> (b_[pos_ + 1])) << 8));
    pos_ += 2;
    return static_cast<std::int16_t> (v);
  }
  float f32 ()
  {
    const std::uint32_t b = u32 ();
    float v;
    std::memcpy (&v, &b, 4);
    return v;
  }
  std::string str (std::size_t max, const char *what)
  {
    const std::uint32_t n = u32 ();
    if (n > max)
      fail (std::string (what) + " of " + std::to_string (n) + " bytes (at most " + std::to_string (max) + ")");
    need (n, what);
    std::string s = b_.substr (pos_, n);
    pos_ += n;
    return s;
  }
  std::size_t pos () const { return pos_; }
  std::size_t left () const { return b_.size () - pos_; }

private:
  const std::string &b_;
  const std::string &name_;
  std::size_t pos_ = 0;
};

std::uint32_t
crc32 (const char *data, std::size_t n)
{
  boost::crc_32_type crc;
  crc.process_bytes (data, n);
  return crc.checksum ();
}
}  // namespace

// --- construction and checks -------------------------------------------------------------

BodyPartForest::BodyPartForest (std::vector<ClassInfo> classes, std::vector<Tree> trees, float reference_focal,
                                VoteRule rule, int background_class)
  : classes_ (std::move (classes)), trees_ (std::move (trees)), reference_focal_ (reference_focal), rule_ (rule),
    background_class_ (background_class)
{
  check ();
}

void
BodyPartForest::check () const
{
  const int C = numClasses ();
  if (C < 1 || C > kMaxClasses)
    throw ModelError ("a forest needs 1 to " + std::to_string (kMaxClasses) + " classes, not " + std::to_string (C));
  for (const auto &c : classes_)
  {
    if (c.name.empty () || c.name.size () > kMaxNameLength)
      throw ModelError ("class names must have 1 to " + std::to_string (kMaxNameLength) + " characters");
    if (c.part < -1 || c.part >= kLabelPartCount)
      throw ModelError ("class '" + c.name + "' maps to part " + std::to_string (c.part) + " (not -1..3)");
  }
  if (trees_.empty () || trees_.size () > static_cast<std::size_t> (kMaxTrees))
    throw ModelError ("a forest needs 1 to " + std::to_string (kMaxTrees) + " trees, not " + std::to_string (trees_.size ()));
  if (!(reference_focal_ >= kMinReferenceFocal && reference_focal_ <= kMaxReferenceFocal))
  {
    std::ostringstream text;
    text << "the reference focal length " << reference_focal_ << " px lies outside " << kMinReferenceFocal << " to "
         << kMaxReferenceFocal << " px";
    throw ModelError (text.str ());
  }
  if (background_class_ < -1 || background_class_ >= C)
    throw ModelError ("background class " + std::to_string (background_class_) + " out of range");
  for (std::size_t t = 0; t < trees_.size (); ++t)
  {
    const Tree &tree = trees_[t];
    const std::string where = "tree " + std::to_string (t) + ": ";
    if (tree.depth < 0 || tree.depth > kMaxDepth || (tree.complete && tree.depth < 1))
      throw ModelError (where + "depth " + std::to_string (tree.depth) + " out of range (at most " +
                        std::to_string (kMaxDepth) + ")");
    for (const auto &n : tree.nodes)
      if (std::isnan (n.threshold))
        throw ModelError (where + "a NaN threshold");
    const std::size_t leaves = tree.leaf_labels.size ();
    if (tree.complete)
    {
      const std::size_t internal = (std::size_t (1) << tree.depth) - 1;
      if (tree.nodes.size () != internal || leaves != internal + 1 || !tree.children.empty ())
        throw ModelError (where + "a complete tree of depth " + std::to_string (tree.depth) + " needs " +
                          std::to_string (internal) + " nodes and " + std::to_string (internal + 1) + " leaves");
    }
    else
    {
      const std::size_t slots = tree.nodes.size ();
      if (slots < 1 || slots > kMaxSparseSlots || tree.children.size () != slots || leaves < 1 || leaves > slots)
        throw ModelError (where + "inconsistent node and leaf counts");
      // Every slot but the root is the child of exactly one earlier slot, every leaf index is
      // used once, and no path is longer than the declared depth: a tree, not a graph.
      std::vector<std::uint8_t> referenced (slots, 0), leaf_used (leaves, 0);
      std::vector<std::int32_t> level (slots, 0);
      for (std::size_t i = 0; i < slots; ++i)
      {
        if (i > 0 && !referenced[i])
          throw ModelError (where + "node " + std::to_string (i) + " is nobody's child");
        const std::int32_t c = tree.children[i];
        if (c >= 0)
        {
          if (static_cast<std::size_t> (c) <= i || static_cast<std::size_t> (c) + 1 >= slots ||
              referenced[c] || referenced[c + 1])
            throw ModelError (where + "node " + std::to_string (i) + " has invalid children");
          referenced[c] = referenced[c + 1] = 1;
          level[c] = level[c + 1] = level[i] + 1;
          if (level[c] > tree.depth)
            throw ModelError (where + "deeper than its declared depth " + std::to_string (tree.depth));
        }
        else
        {
          const std::int64_t leaf = -static_cast<std::int64_t> (c) - 1;
          if (leaf >= static_cast<std::int64_t> (leaves) || leaf_used[leaf])
            throw ModelError (where + "node " + std::to_string (i) + " has an invalid leaf index");
          leaf_used[leaf] = 1;
        }
      }
      if (std::find (leaf_used.begin (), leaf_used.end (), 0) != leaf_used.end ())
        throw ModelError (where + "a leaf that no node reaches");
    }
    for (const auto l : tree.leaf_labels)
      if (l >= C)
        throw ModelError (where + "leaf class " + std::to_string (l) + " out of range");
    if (!tree.leaf_distributions.empty ())
    {
      if (tree.leaf_distributions.size () != leaves * static_cast<std::size_t> (C))
        throw ModelError (where + "leaf distributions of the wrong size");
      for (const float p : tree.leaf_distributions)
        if (!std::isfinite (p) || p < 0.f || p > 1.0001f)
          throw ModelError (where + "a leaf probability outside [0, 1]");
    }
  }
}

std::size_t
BodyPartForest::memoryBytes () const
{
  std::size_t bytes = 0;
  for (const auto &t : trees_)
    bytes += t.nodes.size () * sizeof (Node) + t.children.size () * 4 + t.leaf_labels.size () +
             t.leaf_distributions.size () * sizeof (float);
  return bytes;
}

int
BodyPartForest::leafOf (int t, const ForestDepthImage &depth, int u, int v, float su, float sv) const
{
  return descendTree (trees_.at (static_cast<std::size_t> (t)), depth, u, v, su, sv);
}

// --- evaluation ------------------------------------------------------------------------------

bool
BodyPartForest::evaluate (const ForestDepthImage &depth, const pcl::Indices &pixels, const EvaluationOptions &options,
                          Evaluation &output) const
{
  const int C = numClasses ();
  output.num_classes = options.part_probabilities ? kLabelPartCount : C;
  output.per_part = options.part_probabilities;
  output.probabilities.assign (pixels.size () * static_cast<std::size_t> (output.num_classes), 0.f);
  output.labels.assign (pixels.size (), -1);
  output.evaluated = 0;
  if (empty ())
  {
    PCL_ERROR ("[agex::BodyPartForest::evaluate] The forest is empty (not loaded or trained).\n");
    return false;
  }
  if (options.stride < 1)
  {
    PCL_ERROR ("[agex::BodyPartForest::evaluate] The stride must be at least 1 (is %d).\n", options.stride);
    return false;
  }
  const float fx = options.fx > 0.f ? options.fx : reference_focal_;
  const float fy = options.fy > 0.f ? options.fy : reference_focal_;
  const double rx = static_cast<double> (fx) / reference_focal_, ry = static_cast<double> (fy) / reference_focal_;
  // Bounded so that a probe coordinate (int16 offset x scale) always fits an int.
  if (!std::isfinite (fx) || !std::isfinite (fy) || !(rx <= 50.0) || !(ry <= 50.0) || !(options.fx >= 0.f) ||
      !(options.fy >= 0.f))
  {
    PCL_ERROR ("[agex::BodyPartForest::evaluate] Focal lengths %g, %g: not finite and positive, or more than 50 "
               "times the forest's %g.\n", options.fx, options.fy, reference_focal_);
    return false;
  }
  // 1000 * f / f_ref in float, exactly 1000 (PCL's constant) at the reference focal length.
  const float Fu = static_cast<float> (kFeatureScale * rx), Fv = static_cast<float> (kFeatureScale * ry);
  if (depth.empty () || pixels.empty ())
    return true;

  const int W = depth.width (), H = depth.height (), x0 = depth.x0 (), y0 = depth.y0 ();
  const int fw = depth.frameWidth (), fh = depth.frameHeight ();
  const long long frame_pixels = static_cast<long long> (fw) * fh;
  const std::size_t window = static_cast<std::size_t> (W) * H;
  const std::uint16_t *img = depth.data ();
  auto valid = [] (std::uint16_t d) { return d != ForestDepthImage::kNoData && d != ForestDepthImage::kBackground; };

  // 1: the pixels to run the trees on. Bit 1: an output pixel; bit 2: a candidate.
  std::vector<std::uint8_t> mark (window, 0);
  for (const auto i : pixels)
  {
    if (i < 0 || i >= frame_pixels)
      continue;
    const int u = static_cast<int> (i % fw), v = static_cast<int> (i / fw);
    if (!depth.contains (u, v))
      continue;
    const std::size_t k = static_cast<std::size_t> (v - y0) * W + (u - x0);
    if (valid (img[k]))
      mark[k] = 3;
  }
  if (options.pcl_smoothing)  // the neighbours' labels are needed: the whole foreground
    for (std::size_t k = 0; k < window; ++k)
      if (valid (img[k]))
        mark[k] |= 2;

  // Representatives: per stride cell (cells at multiples of the stride in frame
  // coordinates), its first candidate in row-major order. slot: the representative's entry.
  const int s = options.stride;
  std::vector<std::int32_t> slot (window, -1);
  std::vector<std::int32_t> entry_pixel;  // window index of each entry
  const int cx0 = x0 / s, cy0 = y0 / s;
  const int ncx = (x0 + W - 1) / s - cx0 + 1, ncy = (y0 + H - 1) / s - cy0 + 1;
  std::vector<std::int32_t> cell (s > 1 ? static_cast<std::size_t> (ncx) * ncy : 0, -1);
  {
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
      {
        const std::size_t k = static_cast<std::size_t> (y) * W + x;
        if (!(mark[k] & 2))
          continue;
        if (s == 1)
        {
          slot[k] = static_cast<std::int32_t> (entry_pixel.size ());
          entry_pixel.push_back (static_cast<std::int32_t> (k));
          continue;
        }
        const std::size_t c = static_cast<std::size_t> ((y0 + y) / s - cy0) * ncx + ((x0 + x) / s - cx0);
        if (cell[c] < 0)
        {
          cell[c] = static_cast<std::int32_t> (entry_pixel.size ());
          entry_pixel.push_back (static_cast<std::int32_t> (k));
        }
        slot[k] = cell[c];
      }
  }
  const std::size_t E = entry_pixel.size ();
  const std::size_t T = trees_.size ();
  const bool pcl_vote = rule_ == VoteRule::PclMajority;
  // Output columns: the classes, or the parts they count for.
  const int G = options.part_probabilities ? kLabelPartCount : C;
  std::vector<int> column (C);
  for (int c = 0; c < C; ++c)
    column[c] = options.part_probabilities ? classPart (c) : c;
  std::vector<float> probabilities (E * G, 0.f);
  std::vector<std::uint8_t> tree_labels (pcl_vote ? E * T : 0);
  std::vector<std::int32_t> label (E, -1);
  const float vote = 1.f / static_cast<float> (T);

  // 2: the trees, kBatch pixels at a time; the Average vote's winner right away.
  const bool fma = haveFma () && !options.generic_kernel;
  parallelFor (E, options.threads, [&] (std::size_t b, std::size_t e) {
    int us[kBatch], vs[kBatch], leaves[kBatch];
    float sus[kBatch], svs[kBatch];
    std::vector<float> acc (static_cast<std::size_t> (kBatch) * C);
    for (std::size_t i0 = b; i0 < e; i0 += kBatch)
    {
      const int n = static_cast<int> (std::min<std::size_t> (kBatch, e - i0));
      for (int j = 0; j < n; ++j)
      {
        const int k = entry_pixel[i0 + j];
        us[j] = x0 + k % W;
        vs[j] = y0 + k / W;
        scales (Fu, Fv, img[k], sus[j], svs[j]);
      }
      std::fill (acc.begin (), acc.begin () + static_cast<std::ptrdiff_t> (n) * C, 0.f);
      for (std::size_t t = 0; t < T; ++t)
      {
        const Tree &tree = trees_[t];
        if (fma)
          descendBatchFma (tree, depth, us, vs, sus, svs, n, leaves);
        else
          descendBatch (tree, depth, us, vs, sus, svs, n, leaves);
        for (int j = 0; j < n; ++j)
        {
          const int leaf = leaves[j];
          if (pcl_vote)
            tree_labels[(i0 + j) * T + t] = tree.leaf_labels[leaf];
          float *p = &acc[static_cast<std::size_t> (j) * C];
          if (tree.leaf_distributions.empty ())
            p[tree.leaf_labels[leaf]] += vote;
          else
          {
            const float *q = &tree.leaf_distributions[static_cast<std::size_t> (leaf) * C];
            for (int c = 0; c < C; ++c)
              p[c] += q[c] * vote;
          }
        }
      }
      for (int j = 0; j < n; ++j)
      {
        const float *p = &acc[static_cast<std::size_t> (j) * C];
        if (!pcl_vote)
          label[i0 + j] = static_cast<std::int32_t> (std::max_element (p, p + C) - p);  // first maximum
        float *out = &probabilities[(i0 + j) * G];
        for (int c = 0; c < C; ++c)
          if (column[c] >= 0 && p[c] != 0.f)
            out[column[c]] += p[c];
      }
    }
  });

  // 3: PCL's vote.
  std::atomic<std::size_t> extra (0);
  if (pcl_vote)
    parallelFor (E, options.threads, [&] (std::size_t b, std::size_t e) {
      // bins stays zero between pixels: only the labels voted for are touched and reset.
      std::vector<int> bins (C, 0);
      std::vector<int> touched;
      std::size_t lazy = 0;
      auto add = [&] (int l, int count) {
        if (bins[l] == 0)
          touched.push_back (l);
        bins[l] += count;
      };
      // The most voted label, the lowest on a tie; ties counts the labels with that count.
      auto best = [&] (int &ties) {
        int id = -1, val = 0;
        ties = 0;
        for (const int l : touched)
          if (bins[l] > val || (bins[l] == val && l < id))
          {
            if (bins[l] > val)
              ties = 0;
            id = l;
            val = bins[l];
          }
        for (const int l : touched)
          ties += bins[l] == val ? 1 : 0;
        return id;
      };
      for (std::size_t i = b; i < e; ++i)
      {
        for (std::size_t t = 0; t < T; ++t)
          add (tree_labels[i * T + t], 1);
        // findMaxId_testTie: no winner if two labels share the maximum count.
        int ties = 0;
        int winner = best (ties);
        if (ties > 1)
        {
          // The 3x3 neighbourhood (clamped like the texture; the pixel itself again) of
          // pixels less than 50 mm away in depth adds its trees' votes; findMaxId (the lowest
          // label with the maximum). With a stride s, the neighbours are the representatives
          // of the 3x3 neighbouring cells.
          const int k = entry_pixel[i];
          const int u = x0 + k % W, v = y0 + k / W;
          const int d = img[k];
          for (int di = -1; di <= 1; ++di)
            for (int dj = -1; dj <= 1; ++dj)
            {
              const int nu = std::clamp (u + di * s, 0, fw - 1), nv = std::clamp (v + dj * s, 0, fh - 1);
              const bool inside = depth.contains (nu, nv);
              std::int32_t en = -1;
              if (inside && s == 1)
                en = slot[static_cast<std::size_t> (nv - y0) * W + (nu - x0)];
              else if (inside)
              {
                const int cu = nu / s - cx0, cv = nv / s - cy0;
                if (cu >= 0 && cv >= 0 && cu < ncx && cv < ncy)
                  en = cell[static_cast<std::size_t> (cv) * ncx + cu];
              }
              const int dn = en >= 0 ? img[entry_pixel[en]] : depth.at (nu, nv);
              if (std::abs (d - dn) >= 50)
                continue;
              if (en >= 0)
              {
                for (std::size_t t = 0; t < T; ++t)
                  add (tree_labels[en * T + t], 1);
                continue;
              }
              if (dn == ForestDepthImage::kBackground)
              {
                if (background_class_ >= 0)
                  add (background_class_, static_cast<int> (T));
                continue;
              }
              if (dn == ForestDepthImage::kNoData || s > 1)
                continue;  // PCL would run its trees at an infinite scale on no-data pixels
              // A measured pixel that was not asked for (the ring around the foreground):
              // PCL runs its trees there too.
              float su, sv;
              scales (Fu, Fv, static_cast<std::uint16_t> (dn), su, sv);
              for (std::size_t t = 0; t < T; ++t)
                add (trees_[t].leaf_labels[descendTree (trees_[t], depth, nu, nv, su, sv)], 1);
              ++lazy;
            }
          winner = best (ties);
        }
        label[i] = winner;
        for (const int l : touched)
          bins[l] = 0;
        touched.clear ();
      }
      extra += lazy;
    });

  // 4: PCL's smoothing of the labels.
  std::vector<std::int32_t> smoothed;
  if (options.pcl_smoothing)
  {
    smoothed = label;
    const bool copy = options.fill == StrideFill::Copy;
    auto labelAt = [&] (int u, int v) -> int {
      if (!depth.contains (u, v))
        return background_class_;
      const std::size_t k = static_cast<std::size_t> (v - y0) * W + (u - x0);
      const std::int32_t e = slot[k];
      if (e < 0)
        return img[k] == ForestDepthImage::kBackground ? background_class_ : -1;
      if (!copy && static_cast<std::size_t> (entry_pixel[e]) != k)
        return -1;
      return label[e];
    };
    parallelFor (E, options.threads, [&] (std::size_t b, std::size_t e) {
      std::vector<int> hist (C);
      for (std::size_t i = b; i < e; ++i)
      {
        const int k = entry_pixel[i];
        const int u = x0 + k % W, v = y0 + k / W;
        if (u < 2 || v < 2 || u >= fw - 2 || v >= fh - 2)
          continue;  // PCL's kernel never writes the 2-pixel border
        const int dc = img[k];
        std::fill (hist.begin (), hist.end (), 0);
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx)
          {
            if (std::abs (static_cast<int> (depth.at (u + dx, v + dy)) - dc) >= 300)
              continue;
            const int l = labelAt (u + dx, v + dy);
            if (l >= 0 && classPart (l) >= 0)
              ++hist[l];
          }
        int best = label[i], best_count = 0;
        for (int c = 0; c < C; ++c)
          if (hist[c] > best_count)
          {
            best_count = hist[c];
            best = c;
          }
        smoothed[i] = best;
      }
    });
  }
  const std::vector<std::int32_t> &final_label = options.pcl_smoothing ? smoothed : label;

  // 5: the output, per given pixel.
  for (std::size_t j = 0; j < pixels.size (); ++j)
  {
    const auto i = pixels[j];
    if (i < 0 || i >= frame_pixels)
      continue;
    const int u = static_cast<int> (i % fw), v = static_cast<int> (i / fw);
    if (!depth.contains (u, v))
      continue;
    const std::size_t k = static_cast<std::size_t> (v - y0) * W + (u - x0);
    if (!(mark[k] & 1) || slot[k] < 0)
      continue;
    const std::size_t e = static_cast<std::size_t> (slot[k]);
    if (options.fill == StrideFill::Unlabelled && static_cast<std::size_t> (entry_pixel[e]) != k)
      continue;
    std::copy_n (&probabilities[e * G], G, &output.probabilities[j * G]);
    output.labels[j] = final_label[e];
  }
  output.evaluated = E + extra.load ();
  return true;
}

// --- our model file ----------------------------------------------------------------------------

std::string
BodyPartForest::serialize (const std::string &metadata) const
{
  check ();
  if (metadata.size () > kMaxMetadata)
    throw std::runtime_error ("forest metadata larger than 16 MB");
  Writer w;
  w.bytes (kMagic, 8);
  w.u32 (kFormatVersion);
  w.u64 (0);  // the file's size, filled in below
  w.u32 (static_cast<std::uint32_t> (classes_.size ()));
  w.u32 (static_cast<std::uint32_t> (trees_.size ()));
  w.u32 (rule_ == VoteRule::PclMajority ? 1u : 0u);
  w.i32 (background_class_);
  w.f32 (reference_focal_);
  for (const auto &c : classes_)
  {
    w.str (c.name);
    w.i32 (c.part);
  }
  w.str (metadata);
  for (const auto &t : trees_)
  {
    w.u32 (t.complete ? 0u : 1u);
    w.u32 (static_cast<std::uint32_t> (t.depth));
    w.u32 (static_cast<std::uint32_t> (t.nodes.size ()));
    w.u32 (static_cast<std::uint32_t> (t.leaf_labels.size ()));
    w.u32 (t.leaf_distributions.empty () ? 0u : 1u);
    for (const auto &n : t.nodes)
    {
      w.i16 (n.du1);
      w.i16 (n.dv1);
      w.i16 (n.du2);
      w.i16 (n.dv2);
      w.f32 (n.threshold);
    }
    for (const auto c : t.children)
      w.i32 (c);
    w.bytes (t.leaf_labels.data (), t.leaf_labels.size ());
    for (const float p : t.leaf_distributions)
      w.f32 (p);
  }
  std::string &out = w.buffer ();
  const std::uint64_t size = out.size () + 4;
  for (int i = 0; i < 8; ++i)
    out[12 + i] = static_cast<char> (static_cast<std::uint8_t> (size >> (8 * i)));
  const std::uint32_t crc = crc32 (out.data (), out.size ());
  w.u32 (crc);
  return std::move (out);
}

void
BodyPartForest::save (const std::string &path, const std::string &metadata) const
{
  writeFileAtomic (path, serialize (metadata));
}

BodyPartForest::Ptr
BodyPartForest::deserialize (const std::string &bytes, const std::string &name)
{
  Reader r (bytes, name);
  if (bytes.size () < 8 || std::memcmp (bytes.data (), kMagic, 8) != 0)
    throw ModelError (name + ": not an agex body-part forest (no AGEXFRST magic)");
  (void) r.u64 ();  // the magic
  const std::uint32_t version = r.u32 ();
  if (version != kFormatVersion)
    throw ModelError (name + ": forest format version " + std::to_string (version) + ", this agex reads version " +
                      std::to_string (kFormatVersion));
  const std::uint64_t size = r.u64 ();
  if (size != bytes.size ())
    throw ModelError (name + (size > bytes.size () ? ": truncated: " : ": trailing bytes: ") + std::to_string (bytes.size ()) +
                      " bytes, the header says " + std::to_string (size));
  const std::uint32_t stored_crc = static_cast<std::uint32_t> (static_cast<std::uint8_t> (bytes[size - 4])) |
                                   static_cast<std::uint32_t> (static_cast<std::uint8_t> (bytes[size - 3])) << 8 |
                                   static_cast<std::uint32_t> (static_cast<std::uint8_t> (bytes[size - 2])) << 16 |
                                   static_cast<std::uint32_t> (static_cast<std::uint8_t> (bytes[size - 1])) << 24;
  if (crc32 (bytes.data (), bytes.size () - 4) != stored_crc)
    throw ModelError (name + ": damaged (checksum mismatch)");

  const std::uint32_t C = r.u32 (), T = r.u32 (), rule = r.u32 ();
  const std::int32_t background = r.i32 ();
  const float focal = r.f32 ();
  if (C < 1 || C > static_cast<std::uint32_t> (kMaxClasses))
    r.fail (std::to_string (C) + " classes (1 to " + std::to_string (kMaxClasses) + ")");
  if (T < 1 || T > static_cast<std::uint32_t> (kMaxTrees))
    r.fail (std::to_string (T) + " trees (1 to " + std::to_string (kMaxTrees) + ")");
  if (rule > 1)
    r.fail ("unknown vote rule " + std::to_string (rule));
  std::vector<ClassInfo> classes (C);
  for (auto &c : classes)
  {
    c.name = r.str (kMaxNameLength, "a class name");
    c.part = r.i32 ();
  }
  std::string metadata = r.str (kMaxMetadata, "the metadata");
  std::vector<Tree> trees (T);
  for (std::uint32_t t = 0; t < T; ++t)
  {
    Tree &tree = trees[t];
    const std::string where = "tree " + std::to_string (t) + ": ";
    const std::uint32_t layout = r.u32 (), depth = r.u32 (), nodes = r.u32 (), leaves = r.u32 (), dist = r.u32 ();
    if (layout > 1 || dist > 1)
      r.fail (where + "unknown layout or leaf kind");
    if (depth > static_cast<std::uint32_t> (kMaxDepth))
      r.fail (where + "depth " + std::to_string (depth) + " (at most " + std::to_string (kMaxDepth) + ")");
    if (nodes > kMaxSparseSlots || leaves > kMaxSparseSlots)
      r.fail (where + "too many nodes");
    tree.complete = layout == 0;
    tree.depth = static_cast<int> (depth);
    // Sizes are checked against what is left of the file before anything is allocated.
    const std::uint64_t need = std::uint64_t (nodes) * 12 + (tree.complete ? 0 : std::uint64_t (nodes) * 4) + leaves +
                               (dist ? std::uint64_t (leaves) * C * 4 : 0);
    r.need (need, "a tree's nodes and leaves");
    tree.nodes.resize (nodes);
    for (auto &n : tree.nodes)
    {
      n.du1 = r.i16 ();
      n.dv1 = r.i16 ();
      n.du2 = r.i16 ();
      n.dv2 = r.i16 ();
      n.threshold = r.f32 ();
    }
    if (!tree.complete)
    {
      tree.children.resize (nodes);
      for (auto &c : tree.children)
        c = r.i32 ();
    }
    tree.leaf_labels.resize (leaves);
    for (auto &l : tree.leaf_labels)
      l = r.u8 ();
    if (dist)
    {
      tree.leaf_distributions.resize (std::size_t (leaves) * C);
      for (auto &p : tree.leaf_distributions)
        p = r.f32 ();
    }
  }
  if (r.left () != 4)
    r.fail ("unexpected bytes after the last tree");
  try
  {
    auto forest = std::make_shared<BodyPartForest> (std::move (classes), std::move (trees), focal,
                                                    rule == 1 ? VoteRule::PclMajority : VoteRule::Average, background);
    forest->metadata_ = std::move (metadata);
    return forest;
  }
  catch (const ModelError &e)
  {
    throw ModelError (name + ": " + e.what ());
  }
}

BodyPartForest::Ptr
BodyPartForest::load (const std::string &path)
{
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory (path, ec))
    return loadPclTrees (findPclTreeFiles (path));
  if (!fs::is_regular_file (path, ec))
    throw ModelError (path + ": no such forest file or directory");
  const auto size = fs::file_size (path, ec);
  if (ec)
    throw ModelError (path + ": cannot read (" + ec.message () + ")");
  std::ifstream in (path, std::ios::binary);
  char head[8] = {};
  in.read (head, 8);
  if (!in || std::memcmp (head, kMagic, 8) != 0)
    return loadPclTrees ({path});  // not ours: PCL's text format (plain or bzip2)
  if (size > kMaxFileBytes)
    throw ModelError (path + ": " + std::to_string (size) + " bytes, larger than any forest");
  std::string bytes (static_cast<std::size_t> (size), '\0');
  in.seekg (0);
  in.read (bytes.data (), static_cast<std::streamsize> (size));
  if (static_cast<std::uintmax_t> (in.gcount ()) != size)
    throw ModelError (path + ": cannot read the whole file");
  return deserialize (bytes, path);
}
}  // namespace agex

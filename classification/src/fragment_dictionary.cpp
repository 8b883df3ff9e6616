#include <agex/classification/fragment_dictionary.h>

#include "checked_read.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace agex
{
namespace
{
constexpr int kMaxSize = agex::DepthPatch::kMaxSize;
/** A cut is flat when its variance is below this fraction of its sum of squares. */
constexpr double kFlatRelative = 1e-9;
/** Redraws of a flat cut before the fragment is kept all zero. */
constexpr int kCutAttempts = 100;

// ---------------------------------------------------------------------------------------
// The feature kernel (fragment_kernel.inc), in 16-bit fixed point.
//
// The patch is quantised once per call: cells minus their mid-range, scaled so that the
// largest magnitude is kPatchScale (7200), rounded. A fragment is quantised when the
// dictionary is built or read: values times fragmentScale (size), rounded. Each fragment row
// is packed as 32-bit words holding two neighbouring columns, and the patch as words holding
// each cell with its right neighbour, so one pmaddwd multiplies two columns for a whole
// vector of window positions and adds them in 32-bit lanes. Integer sums are exact, and the
// scales keep every sum below 2^31 (Cauchy-Schwarz: |sum| <= |f| |p| <= fragmentScale x 1
// x kPatchScale x size).
//
// Per position, with integral images of the quantised patch (int32 sums, int64 sums of
// squares) and the fragment's sum and sum of squares, the Pearson correlation of the two
// quantised pieces is cov / sqrt (var_p var_f); area x var_p is computed exactly (integers
// below 2^53, in double), so a flat window (var_p = 0) is recognised exactly and correlates
// 0; area x cov is computed in float. The best signed square cov |cov| / var_p is kept per
// lane, one square root at the end.
//
// Kernels: "avx-vnni" (8 positions per vector, fused dot-product-and-add), "avx2" (8
// positions, pmaddwd then add), "sse2" (4 positions) on x86-64 with GCC, chosen at run
// time, and "generic" (plain C++, one position at a time) everywhere. They perform the same
// IEEE operations in the same order (no fused multiply-adds: -ffp-contract=off), so they
// give the same bits.
constexpr int kPad = 8;               ///< padding after each row / array: the widest load is 8
constexpr double kPatchScale = 7200;  ///< largest |quantised patch cell| (41 x 7200^2 < 2^31)

/** Fixed-point scale of a size x size fragment: sums stay below 0.99 x 2^31. */
int
fragmentScale (int size)
{
  const double bound = 0.99 * 2147483648.0 / (kPatchScale * size);
  return static_cast<int> (std::min (32767.0, std::floor (bound)));
}

/** floor (v + 0.5) for |v| < 65536, without branches and without rounding-mode state:
  * truncation of a positive number is its floor. */
inline int
roundToInt (double v)
{
  return static_cast<int> (v + 65536.5) - 65536;
}

using Packed = FragmentDictionary::Packed;

/** The patch, quantised and packed in pairs (words[r * stride + x] holds cells x and x + 1
  * of row r, 0 beyond the row), with integral images of the quantised cells (int32) and of
  * their squares (int64): sum[y * (n + 1) + x] = sum of the cells above y and left of x. */
struct Prepared
{
  int n = 0;
  int stride = 0;  ///< words per padded row
  std::int32_t pairs[kMaxSize * (kMaxSize + kPad)];
  std::int32_t sum[(kMaxSize + 1) * (kMaxSize + 1) + kPad];
  std::int64_t sq[(kMaxSize + 1) * (kMaxSize + 1) + kPad];

  void prepare (const agex::DepthPatch &patch)
  {
    n = patch.size;
    stride = n + kPad;
    // Locals only below: stores into the member arrays could alias members as far as the
    // compiler knows, which would keep the loops from vectorising.
    const int n = patch.size, stride = n + kPad;
    const int cells = n * n, w = n + 1;
    std::int32_t *const pairs = this->pairs;
    std::int32_t *const sum = this->sum;
    std::int64_t *const sq = this->sq;

    // Mid-range and scale of the finite cells; a non-finite cell reads as the largest
    // finite one.
    float lo, hi;
    extremes (patch.patch, cells, lo, hi);
    if (!(hi >= lo))  // no finite cell
      lo = hi = 0.f;
    const double mid = 0.5 * (static_cast<double> (lo) + static_cast<double> (hi));
    const double range = 0.5 * (static_cast<double> (hi) - static_cast<double> (lo));
    const double scale = range > 0.0 ? kPatchScale / range : 0.0;
    // Quantised cells, |q| <= 7200: floor ((v - mid) scale + 0.5) in float (plenty for
    // integers up to 7200; int32 here so that the loop vectorises).
    std::int32_t q[kMaxSize * kMaxSize];
    const float fill = hi, fmid = static_cast<float> (mid), fscale = static_cast<float> (scale);
    for (int i = 0; i < cells; ++i)
    {
      const float v = patch.patch[i];
      const float d = std::fabs (v) <= std::numeric_limits<float>::max () ? v : fill;  // NaN, +-inf: fill
      q[i] = static_cast<std::int32_t> ((d - fmid) * fscale + 16384.5f) - 16384;
    }
    for (int r = 0; r < n; ++r)
    {
      std::int32_t *__restrict row = pairs + r * stride;
      const std::int32_t *__restrict src = q + r * n;
      for (int c = 0; c + 1 < n; ++c)
        row[c] = static_cast<std::int32_t> ((static_cast<std::uint32_t> (src[c]) & 0xffffu) |
                                            (static_cast<std::uint32_t> (src[c + 1]) << 16));
      row[n - 1] = static_cast<std::int32_t> (static_cast<std::uint32_t> (src[n - 1]) & 0xffffu);
      for (int c = n; c < stride; ++c)
        row[c] = 0;
    }
    // Integral images: row prefix sums (a row of squares stays below 41 x 7200^2 < 2^31),
    // four rows at a time (independent chains), into rows 1..n; then down the columns.
    for (int x = 0; x < w; ++x)
    {
      sum[x] = 0;
      sq[x] = 0;
    }
    int r = 0;
    for (; r + 4 <= n; r += 4)
    {
      std::int32_t a[4] = {0, 0, 0, 0}, b[4] = {0, 0, 0, 0};
      for (int j = 0; j < 4; ++j)
      {
        sum[(r + j + 1) * w] = 0;
        sq[(r + j + 1) * w] = 0;
      }
      for (int c = 0; c < n; ++c)
        for (int j = 0; j < 4; ++j)
        {
          const std::int32_t v = q[(r + j) * n + c];
          a[j] += v;
          b[j] += v * v;
          sum[(r + j + 1) * w + c + 1] = a[j];
          sq[(r + j + 1) * w + c + 1] = b[j];
        }
    }
    for (; r < n; ++r)
    {
      std::int32_t a = 0, b = 0;
      sum[(r + 1) * w] = 0;
      sq[(r + 1) * w] = 0;
      for (int c = 0; c < n; ++c)
      {
        const std::int32_t v = q[r * n + c];
        a += v;
        b += v * v;
        sum[(r + 1) * w + c + 1] = a;
        sq[(r + 1) * w + c + 1] = b;
      }
    }
    for (int y = 2; y <= n; ++y)
    {
      std::int32_t *__restrict cs = sum + y * w;
      std::int64_t *__restrict cq = sq + y * w;
      const std::int32_t *__restrict ps = cs - w;
      const std::int64_t *__restrict pq = cq - w;
      for (int x = 0; x < w; ++x)
      {
        cs[x] += ps[x];
        cq[x] += pq[x];
      }
    }
    for (int i = 0; i < kPad; ++i)
    {
      sum[w * w + i] = 0;
      sq[w * w + i] = 0;
    }
  }

  /** Smallest and largest finite value (+inf / -inf if none). */
  static void extremes (const float *v, int count, float &lo, float &hi)
  {
    constexpr float inf = std::numeric_limits<float>::infinity ();
    int i = 0;
    lo = inf;
    hi = -inf;
#if defined(__GNUC__) && !defined(__clang__)
    typedef float V4 __attribute__ ((vector_size (16)));
    V4 l = inf - V4{}, h = -inf - V4{};
    for (; i + 4 <= count; i += 4)
    {
      V4 x;
      std::memcpy (&x, v + i, sizeof x);
      l = x < l ? x : l;  // NaN compares false: ignored; -inf/+inf are not taken below
      h = x > h ? x : h;
    }
    for (int j = 0; j < 4; ++j)
    {
      lo = l[j] < lo ? l[j] : lo;
      hi = h[j] > hi ? h[j] : hi;
    }
#endif
    for (; i < count; ++i)
    {
      lo = v[i] < lo ? v[i] : lo;
      hi = v[i] > hi ? v[i] : hi;
    }
    // Infinite cells are not finite: recompute without them if there are any.
    if (lo == -inf || hi == inf)
    {
      lo = inf;
      hi = -inf;
      for (i = 0; i < count; ++i)
        if (std::fabs (v[i]) <= std::numeric_limits<float>::max ())
        {
          lo = v[i] < lo ? v[i] : lo;
          hi = v[i] > hi ? v[i] : hi;
        }
    }
  }
};

/** Exact conversion of integers in [0, 2^52) to double (the vector kernels convert int64
  * with the same arithmetic, see fragment_kernel.inc). */
inline double
exactDouble (std::int64_t v)
{
  return static_cast<double> (v);
}

/** The feature from the best lane score m (signed square, times the fragment's norm). */
inline float
finishFeature (float m, const Packed &f)
{
  if (!(m != 0.f) || !(f.norm > 0.0))
    return 0.f;  // +0 also for a -0 score
  const double r2 = std::fabs (static_cast<double> (m)) / f.norm;
  const double ncc = m > 0.f ? std::sqrt (r2) : -std::sqrt (r2);
  return static_cast<float> (std::clamp (ncc, -1.0, 1.0));
}

constexpr float kBest = -std::numeric_limits<float>::infinity ();

namespace kernel_generic
{
// Plain C++: the same arithmetic as the vector kernels, one position at a time.
float
fragmentFeature (const Prepared &p, const Packed &f, const Fragment &g)
{
  const int s = f.size, w = g.window_radius, last = p.n - s, iw = p.n + 1;
  const double area = static_cast<double> (s) * s;
  float best = kBest;
  for (int py = std::max (0, g.y - w); py <= std::min (last, g.y + w); ++py)
    for (int px = std::max (0, g.x - w); px <= std::min (last, g.x + w); ++px)
    {
      std::int32_t num = 0;
      for (int r = 0; r < s; ++r)
        for (int j = 0; j < f.pairs; ++j)
        {
          const std::int32_t a = f.words[static_cast<std::size_t> (r * f.pairs + j)];
          const std::int32_t b = p.pairs[(py + r) * p.stride + px + 2 * j];
          num += static_cast<std::int16_t> (a & 0xffff) * static_cast<std::int16_t> (b & 0xffff) +
                 static_cast<std::int16_t> (a >> 16) * static_cast<std::int16_t> (b >> 16);
        }
      const std::int32_t *s0 = p.sum + py * iw + px, *s1 = s0 + s * iw;
      const std::int64_t *q0 = p.sq + py * iw + px, *q1 = q0 + s * iw;
      const double sm = static_cast<double> (s1[s] - s1[0] - s0[s] + s0[0]);
      const double sq = exactDouble (q1[s] - q1[0] - q0[s] + q0[0]);
      const float cf = static_cast<float> (area) * static_cast<float> (num) -
                       static_cast<float> (f.sum) * static_cast<float> (s1[s] - s1[0] - s0[s] + s0[0]);
      const float vf = static_cast<float> (area * sq - sm * sm);
      const float score = vf <= 0.f ? 0.f : cf * (cf < 0.f ? -cf : cf) / vf;
      best = score > best ? score : best;
    }
  return finishFeature (best, f);
}

void
computeFeatures (const Prepared &p, const std::vector<Packed> &packed, const std::vector<Fragment> &fragments,
                 const int *which, std::size_t count, float *features)
{
  if (which)
    for (std::size_t i = 0; i < count; ++i)
    {
      const std::size_t f = static_cast<std::size_t> (which[i]);
      features[f] = fragmentFeature (p, packed[f], fragments[f]);
    }
  else
    for (std::size_t f = 0; f < fragments.size (); ++f)
      features[f] = fragmentFeature (p, packed[f], fragments[f]);
}
}  // namespace kernel_generic

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define AGEX_X86_KERNELS 1
#define AGEX_ALWAYS_INLINE inline __attribute__ ((always_inline))

namespace kernel_sse2
{
constexpr int kLanes = 4;
typedef std::int32_t VecI32 __attribute__ ((vector_size (16)));
typedef float VecF __attribute__ ((vector_size (16)));
typedef int VecI __attribute__ ((vector_size (16)));
typedef std::int32_t VecHI __attribute__ ((vector_size (8)));
typedef double VecHD __attribute__ ((vector_size (16)));
typedef float VecHF __attribute__ ((vector_size (8)));
typedef std::int64_t VecHL __attribute__ ((vector_size (16)));
#define AGEX_DOT(acc, q, f) ((acc) + (VecI32) _mm_madd_epi16 ((__m128i) (q), (__m128i) (f)))
#define AGEX_MAX_ROWS 4
#define AGEX_LOW(v) __builtin_shufflevector (v, v, 0, 1)
#define AGEX_HIGH(v) __builtin_shufflevector (v, v, 2, 3)
#define AGEX_CONCAT(a, b) __builtin_shufflevector (a, b, 0, 1, 2, 3)
#include "fragment_kernel.inc"
#undef AGEX_CONCAT
#undef AGEX_HIGH
#undef AGEX_LOW
#undef AGEX_MAX_ROWS
#undef AGEX_DOT
}  // namespace kernel_sse2

#pragma GCC push_options
#pragma GCC target("avx2")
namespace kernel_avx2
{
constexpr int kLanes = 8;
typedef std::int32_t VecI32 __attribute__ ((vector_size (32)));
typedef float VecF __attribute__ ((vector_size (32)));
typedef int VecI __attribute__ ((vector_size (32)));
typedef std::int32_t VecHI __attribute__ ((vector_size (16)));
typedef double VecHD __attribute__ ((vector_size (32)));
typedef float VecHF __attribute__ ((vector_size (16)));
typedef std::int64_t VecHL __attribute__ ((vector_size (32)));
#define AGEX_DOT(acc, q, f) ((acc) + (VecI32) _mm256_madd_epi16 ((__m256i) (q), (__m256i) (f)))
#define AGEX_MAX_ROWS 8
#define AGEX_LOW(v) __builtin_shufflevector (v, v, 0, 1, 2, 3)
#define AGEX_HIGH(v) __builtin_shufflevector (v, v, 4, 5, 6, 7)
#define AGEX_CONCAT(a, b) __builtin_shufflevector (a, b, 0, 1, 2, 3, 4, 5, 6, 7)
#include "fragment_kernel.inc"
#undef AGEX_CONCAT
#undef AGEX_HIGH
#undef AGEX_LOW
#undef AGEX_MAX_ROWS
#undef AGEX_DOT
}  // namespace kernel_avx2
#pragma GCC pop_options

#pragma GCC push_options
#pragma GCC target("avx2,avxvnni")
namespace kernel_vnni
{
constexpr int kLanes = 8;
typedef std::int32_t VecI32 __attribute__ ((vector_size (32)));
typedef float VecF __attribute__ ((vector_size (32)));
typedef int VecI __attribute__ ((vector_size (32)));
typedef std::int32_t VecHI __attribute__ ((vector_size (16)));
typedef double VecHD __attribute__ ((vector_size (32)));
typedef float VecHF __attribute__ ((vector_size (16)));
typedef std::int64_t VecHL __attribute__ ((vector_size (32)));
#define AGEX_DOT(acc, q, f) ((VecI32) _mm256_dpwssd_avx_epi32 ((__m256i) (acc), (__m256i) (q), (__m256i) (f)))
#define AGEX_MAX_ROWS 8
#define AGEX_LOW(v) __builtin_shufflevector (v, v, 0, 1, 2, 3)
#define AGEX_HIGH(v) __builtin_shufflevector (v, v, 4, 5, 6, 7)
#define AGEX_CONCAT(a, b) __builtin_shufflevector (a, b, 0, 1, 2, 3, 4, 5, 6, 7)
#include "fragment_kernel.inc"
#undef AGEX_CONCAT
#undef AGEX_HIGH
#undef AGEX_LOW
#undef AGEX_MAX_ROWS
#undef AGEX_DOT
}  // namespace kernel_vnni
#pragma GCC pop_options
#endif

enum class Kernel
{
  Vnni,
  Avx2,
  Sse2,
  Generic
};

struct KernelInfo
{
  Kernel kernel;
  const char *name;
};

/** The kernels available here, fastest first. */
const std::vector<KernelInfo> &
kernels ()
{
  static const std::vector<KernelInfo> list = [] {
    std::vector<KernelInfo> k;
#ifdef AGEX_X86_KERNELS
    if (__builtin_cpu_supports ("avx2") && __builtin_cpu_supports ("avxvnni"))
      k.push_back ({Kernel::Vnni, "avx-vnni"});
    if (__builtin_cpu_supports ("avx2"))
      k.push_back ({Kernel::Avx2, "avx2"});
    k.push_back ({Kernel::Sse2, "sse2"});
#endif
    k.push_back ({Kernel::Generic, "generic"});
    return k;
  }();
  return list;
}

/** Index into kernels () of the selected kernel (FragmentDictionary::selectKernel). */
std::atomic<int> selected_kernel{0};

void
computeDispatch (const Prepared &p, const std::vector<Packed> &packed, const std::vector<Fragment> &fragments,
                 const int *which, std::size_t count, float *features)
{
  switch (kernels ()[static_cast<std::size_t> (selected_kernel.load (std::memory_order_relaxed))].kernel)
  {
#ifdef AGEX_X86_KERNELS
    case Kernel::Vnni: kernel_vnni::computeFeatures (p, packed, fragments, which, count, features); break;
    case Kernel::Avx2: kernel_avx2::computeFeatures (p, packed, fragments, which, count, features); break;
    case Kernel::Sse2: kernel_sse2::computeFeatures (p, packed, fragments, which, count, features); break;
#endif
    default: kernel_generic::computeFeatures (p, packed, fragments, which, count, features); break;
  }
}

using detail::readInt;
using detail::readString;
}  // namespace

void
FragmentDictionary::build (const std::vector<std::vector<const agex::DepthPatch *>> &positives,
                           const FragmentDictionaryParams &params)
{
  if (positives.empty ())
    throw std::invalid_argument ("FragmentDictionary::build: no classes");
  if (params.fragments_per_class < 1)
    throw std::invalid_argument ("FragmentDictionary::build: fragments_per_class must be at least 1");
  if (params.min_size < 1 || params.max_size < params.min_size)
    throw std::invalid_argument ("FragmentDictionary::build: need 1 <= min_size <= max_size");
  if (params.window_radius < 0)
    throw std::invalid_argument ("FragmentDictionary::build: window_radius must not be negative");
  int n = 0;
  for (std::size_t c = 0; c < positives.size (); ++c)
  {
    if (positives[c].empty ())
      throw std::invalid_argument ("FragmentDictionary::build: class " + std::to_string (c) + " has no positives");
    for (const agex::DepthPatch *patch : positives[c])
    {
      if (!patch)
        throw std::invalid_argument ("FragmentDictionary::build: null patch in class " + std::to_string (c));
      if (patch->size < 1 || patch->size > kMaxSize)
        throw std::invalid_argument ("FragmentDictionary::build: patch size " + std::to_string (patch->size) +
                                     " outside 1.." + std::to_string (kMaxSize));
      if (n == 0)
        n = patch->size;
      else if (patch->size != n)
        throw std::invalid_argument ("FragmentDictionary::build: patches of different sizes (" + std::to_string (n) +
                                     " and " + std::to_string (patch->size) + ")");
    }
  }

  // A fixed generator and plain modulo draws: the same dictionary on every platform
  // (std::uniform_int_distribution is implementation-defined).
  std::mt19937_64 rng (params.seed);
  const auto draw = [&rng] (int count) { return static_cast<int> (rng () % static_cast<std::uint64_t> (count)); };
  const int smin = std::min (params.min_size, n), smax = std::min (params.max_size, n);

  std::vector<Fragment> fragments;
  fragments.reserve (positives.size () * static_cast<std::size_t> (params.fragments_per_class));
  std::vector<double> cut;
  for (std::size_t c = 0; c < positives.size (); ++c)
    for (int k = 0; k < params.fragments_per_class; ++k)
    {
      Fragment f;
      f.cls = static_cast<int> (c);
      f.window_radius = params.window_radius;
      bool flat = true;
      for (int attempt = 0; attempt < kCutAttempts && flat; ++attempt)
      {
        const agex::DepthPatch &patch = *positives[c][draw (static_cast<int> (positives[c].size ()))];
        f.size = smin + draw (smax - smin + 1);
        f.x = draw (n - f.size + 1);
        f.y = draw (n - f.size + 1);
        const int s = f.size;
        cut.resize (static_cast<std::size_t> (s) * s);
        double mean = 0.0, sq = 0.0;
        for (int r = 0; r < s; ++r)
          for (int col = 0; col < s; ++col)
          {
            const double v = patch.patch[(f.y + r) * n + f.x + col];
            cut[r * s + col] = v;
            mean += v;
            sq += v * v;
          }
        mean /= s * s;
        double var = 0.0;
        for (double &v : cut)
        {
          v -= mean;
          var += v * v;
        }
        f.values.assign (cut.size (), 0.f);
        if (!(var > kFlatRelative * sq) || !std::isfinite (var))
          continue;
        flat = false;
        const double inv_norm = 1.0 / std::sqrt (var);
        for (std::size_t i = 0; i < cut.size (); ++i)
          f.values[i] = static_cast<float> (cut[i] * inv_norm);
      }
      fragments.push_back (std::move (f));
    }

  fragments_ = std::move (fragments);
  patch_size_ = n;
  params_ = params;
  pack ();
}

std::vector<std::string>
FragmentDictionary::availableKernels ()
{
  std::vector<std::string> names;
  for (const KernelInfo &k : kernels ())
    names.emplace_back (k.name);
  return names;
}

bool
FragmentDictionary::selectKernel (const std::string &name)
{
  if (name.empty () || name == "auto")
  {
    selected_kernel.store (0, std::memory_order_relaxed);
    return true;
  }
  const std::vector<KernelInfo> &list = kernels ();
  for (std::size_t i = 0; i < list.size (); ++i)
    if (name == list[i].name)
    {
      selected_kernel.store (static_cast<int> (i), std::memory_order_relaxed);
      return true;
    }
  return false;
}

std::string
FragmentDictionary::kernelName ()
{
  return kernels ()[static_cast<std::size_t> (selected_kernel.load (std::memory_order_relaxed))].name;
}

void
FragmentDictionary::pack ()
{
  std::vector<Packed> packed;
  packed.reserve (fragments_.size ());
  for (const Fragment &f : fragments_)
  {
    Packed q;
    q.size = f.size;
    q.pairs = (f.size + 1) / 2;
    q.words.assign (static_cast<std::size_t> (q.size) * q.pairs, 0);
    const double scale = fragmentScale (f.size);
    std::int64_t sum = 0, sq = 0;
    for (int r = 0; r < f.size; ++r)
      for (int c = 0; c < f.size; ++c)
      {
        const int v = std::clamp (roundToInt (static_cast<double> (f.values[r * f.size + c]) * scale), -32767, 32767);
        sum += v;
        sq += static_cast<std::int64_t> (v) * v;
        const std::uint32_t bits = static_cast<std::uint16_t> (static_cast<std::int16_t> (v));
        std::int32_t &word = q.words[static_cast<std::size_t> (r * q.pairs + c / 2)];
        word = static_cast<std::int32_t> (static_cast<std::uint32_t> (word) | (c % 2 ? bits << 16 : bits));
      }
    const std::int64_t area = static_cast<std::int64_t> (f.size) * f.size;
    q.sum = static_cast<double> (sum);
    q.norm = static_cast<double> (area * sq - sum * sum);
    packed.push_back (std::move (q));
  }
  packed_ = std::move (packed);
}

void
FragmentDictionary::computeFeatures (const agex::DepthPatch &patch, float *features) const
{
  if (fragments_.empty ())
    return;
  if (patch.size != patch_size_)
    throw std::invalid_argument ("FragmentDictionary::computeFeatures: patch size " + std::to_string (patch.size) +
                                 ", the dictionary was built for " + std::to_string (patch_size_));
  Prepared p;
  p.prepare (patch);
  computeDispatch (p, packed_, fragments_, nullptr, 0, features);
}

void
FragmentDictionary::computeFeatures (const agex::DepthPatch &patch, const std::vector<int> &which,
                                     float *features) const
{
  if (which.empty ())
    return;
  if (patch.size != patch_size_)
    throw std::invalid_argument ("FragmentDictionary::computeFeatures: patch size " + std::to_string (patch.size) +
                                 ", the dictionary was built for " + std::to_string (patch_size_));
  for (int f : which)
    if (f < 0 || static_cast<std::size_t> (f) >= fragments_.size ())
      throw std::invalid_argument ("FragmentDictionary::computeFeatures: fragment index " + std::to_string (f) +
                                   " out of range");
  Prepared p;
  p.prepare (patch);
  computeDispatch (p, packed_, fragments_, which.data (), which.size (), features);
}

struct FragmentDictionary::PreparedPatch::Impl
{
  Prepared prepared;
};

FragmentDictionary::PreparedPatch::PreparedPatch () = default;
FragmentDictionary::PreparedPatch::~PreparedPatch () = default;
FragmentDictionary::PreparedPatch::PreparedPatch (PreparedPatch &&) noexcept = default;
FragmentDictionary::PreparedPatch &FragmentDictionary::PreparedPatch::operator= (PreparedPatch &&) noexcept = default;

int
FragmentDictionary::PreparedPatch::size () const
{
  return impl_ ? impl_->prepared.n : 0;
}

void
FragmentDictionary::prepare (const agex::DepthPatch &patch, PreparedPatch &prepared) const
{
  if (patch.size != patch_size_ || patch_size_ < 1)
    throw std::invalid_argument ("FragmentDictionary::prepare: patch size " + std::to_string (patch.size) +
                                 ", the dictionary was built for " + std::to_string (patch_size_));
  if (!prepared.impl_)
    prepared.impl_.reset (new PreparedPatch::Impl);  // not value-initialised: prepare () writes what it reads
  prepared.impl_->prepared.prepare (patch);
}

void
FragmentDictionary::computeFeatures (const PreparedPatch &prepared, const int *which, std::size_t count,
                                     float *features) const
{
  if (count == 0)
    return;
  if (prepared.size () != patch_size_ || patch_size_ < 1)
    throw std::invalid_argument ("FragmentDictionary::computeFeatures: the prepared patch is not of size " +
                                 std::to_string (patch_size_));
  computeDispatch (prepared.impl_->prepared, packed_, fragments_, which, count, features);
}

void
FragmentDictionary::write (cv::FileStorage &fs) const
{
  fs << "patch_size" << patch_size_;
  fs << "fragments_per_class" << params_.fragments_per_class;
  fs << "min_size" << params_.min_size;
  fs << "max_size" << params_.max_size;
  fs << "window_radius" << params_.window_radius;
  // FileStorage integers are 32 bits: the 64-bit seed goes as a decimal string.
  fs.write ("seed", std::to_string (params_.seed));
  fs << "fragments" << "[";
  for (const Fragment &f : fragments_)
  {
    fs << "{:";
    fs << "class" << f.cls << "x" << f.x << "y" << f.y << "size" << f.size << "window_radius" << f.window_radius;
    fs << "values" << f.values;  // floats as %.8e: exact, a third shorter than scalars
    fs << "}";
  }
  fs << "]";
}

void
FragmentDictionary::read (const cv::FileNode &node)
{
  if (node.empty () || !node.isMap ())
    throw ModelError ("dictionary: missing or not a map");
  try
  {
    FragmentDictionaryParams params;
    const int n = readInt (node, "patch_size");
    if (n < 1 || n > kMaxSize)
      throw ModelError ("patch_size " + std::to_string (n) + " outside 1.." + std::to_string (kMaxSize));
    params.fragments_per_class = readInt (node, "fragments_per_class");
    params.min_size = readInt (node, "min_size");
    params.max_size = readInt (node, "max_size");
    params.window_radius = readInt (node, "window_radius");
    const std::string seed = readString (node, "seed");
    if (seed.empty () || seed.size () > 20 || seed.find_first_not_of ("0123456789") != std::string::npos)
      throw ModelError ("invalid seed '" + seed + "'");
    try
    {
      params.seed = std::stoull (seed);
    }
    catch (const std::exception &)
    {
      throw ModelError ("invalid seed '" + seed + "'");
    }

    const cv::FileNode list = node["fragments"];
    if (list.empty () || !list.isSeq ())
      throw ModelError ("missing or invalid 'fragments'");
    std::vector<Fragment> fragments;
    fragments.reserve (list.size ());
    int index = 0;
    for (cv::FileNodeIterator it = list.begin (); it != list.end (); ++it, ++index)
    {
      const cv::FileNode fn = *it;
      const std::string where = "fragment " + std::to_string (index) + ": ";
      if (!fn.isMap ())
        throw ModelError (where + "not a map");
      Fragment f;
      try
      {
        f.cls = readInt (fn, "class");
        f.x = readInt (fn, "x");
        f.y = readInt (fn, "y");
        f.size = readInt (fn, "size");
        f.window_radius = readInt (fn, "window_radius");
      }
      catch (const ModelError &e)
      {
        throw ModelError (where + e.what ());
      }
      if (f.cls < 0)
        throw ModelError (where + "negative class");
      if (f.size < 1 || f.size > n)
        throw ModelError (where + "size " + std::to_string (f.size) + " outside 1.." + std::to_string (n));
      if (f.x < 0 || f.y < 0 || f.x + f.size > n || f.y + f.size > n)
        throw ModelError (where + "lies outside the " + std::to_string (n) + "x" + std::to_string (n) + " patch");
      if (f.window_radius < 0 || f.window_radius > n)
        throw ModelError (where + "window_radius " + std::to_string (f.window_radius) + " outside 0.." +
                          std::to_string (n));
      const cv::FileNode values = fn["values"];
      const std::size_t expected = static_cast<std::size_t> (f.size) * f.size;
      if (values.empty () || !values.isSeq () || values.size () != expected)
        throw ModelError (where + "needs " + std::to_string (expected) + " values (size " + std::to_string (f.size) +
                          "), has " + std::to_string (values.isSeq () ? values.size () : 0));
      f.values.reserve (expected);
      double norm = 0.0;
      for (cv::FileNodeIterator v = values.begin (); v != values.end (); ++v)
      {
        const cv::FileNode value = *v;
        if (!value.isReal () && !value.isInt ())
          throw ModelError (where + "a value is not a number");
        const float x = static_cast<float> (value);
        if (!std::isfinite (x))
          throw ModelError (where + "a value is not finite");
        f.values.push_back (x);
        norm += static_cast<double> (x) * x;
      }
      if (norm != 0.0 && std::fabs (norm - 1.0) > 1e-3)
        throw ModelError (where + "values are not normalised");
      fragments.push_back (std::move (f));
    }
    fragments_ = std::move (fragments);
    patch_size_ = n;
    params_ = params;
    pack ();
  }
  catch (const ModelError &e)
  {
    const std::string what = e.what ();
    if (what.rfind ("dictionary: ", 0) == 0)
      throw;
    throw ModelError ("dictionary: " + what);
  }
  catch (const cv::Exception &e)
  {
    throw ModelError ("dictionary: " + e.err);
  }
  catch (const std::exception &e)
  {
    throw ModelError (std::string ("dictionary: ") + e.what ());
  }
}
}  // namespace agex

#pragma once
// Deterministic random numbers for synthetic frames: the same seed gives the same bytes on
// every run and platform with the same floating point.
#include <cstdint>
#include <random>

namespace agex
{
/** Deterministic random numbers: std::mt19937_64 (fully specified by the standard)
  * with uniform and Box-Muller normal variates computed here, never through the
  * implementation-defined std:: distributions. */
class SynthRng
{
public:
  explicit SynthRng (std::uint64_t seed) : engine_ (seed) {}
  /** A generator for item `index` of a run seeded with `seed` (SplitMix64 of both). */
  static SynthRng forItem (std::uint64_t seed, std::uint64_t index);

  std::uint64_t raw () { return engine_ (); }
  /** Uniform in [0, 1), 53 random bits. */
  double uniform ();
  double uniform (double lo, double hi) { return lo + (hi - lo) * uniform (); }
  /** Uniform integer in [0, n). */
  int index (int n);
  /** Standard normal (Box-Muller, both values of a pair are used). */
  double normal ();
  double normal (double mean, double sigma) { return mean + sigma * normal (); }
  bool chance (double p) { return uniform () < p; }

private:
  std::mt19937_64 engine_;
  bool have_spare_ = false;
  double spare_ = 0.0;
};
}  // namespace agex

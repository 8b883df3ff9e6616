// Deterministic random numbers of the synthetic frames.
#include <agex/simulation/synth_rng.h>

#include <algorithm>
#include <cmath>

namespace agex
{
namespace
{
std::uint64_t
splitMix64 (std::uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
}  // namespace

SynthRng
SynthRng::forItem (std::uint64_t seed, std::uint64_t index)
{
  return SynthRng (splitMix64 (splitMix64 (seed) ^ splitMix64 (index + 0x632BE59BD9B4E019ull)));
}

double
SynthRng::uniform ()
{
  return static_cast<double> (engine_ () >> 11) * (1.0 / 9007199254740992.0);
}

int
SynthRng::index (int n)
{
  if (n <= 1)
    return 0;
  return std::min (n - 1, static_cast<int> (uniform () * n));
}

double
SynthRng::normal ()
{
  if (have_spare_)
  {
    have_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform ();  // (0, 1]
  const double u2 = uniform ();
  const double r = std::sqrt (-2.0 * std::log (u1));
  spare_ = r * std::sin (2.0 * M_PI * u2);
  have_spare_ = true;
  return r * std::cos (2.0 * M_PI * u2);
}
}  // namespace agex

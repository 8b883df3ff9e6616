#include <agex/simulation/body_shape.h>
#include <agex/simulation/synth_rng.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace agex
{
namespace
{
// MakeHuman's age scale (human.py MIN_AGE, MID_AGE, MAX_AGE): years at age 0, 0.5 and 1.
constexpr double kYearsAtZero = 1.0, kYearsAtMiddle = 25.0, kYearsAtOne = 90.0;
// Spread of adult stature within a gender, metres (about 7 cm in most populations).
constexpr double kStatureSigma = 0.07;
// MakeHuman's average statures (young man 1.73 m, woman 1.59 m; older ones shorter) lie
// a few centimetres under today's adults': raised by this much, metres.
constexpr double kStatureShift = 0.04;

std::string
fixed (double value, int decimals = 2)
{
  char text[48];
  std::snprintf (text, sizeof text, "%.*f", decimals, value);
  return text;
}
}  // namespace

BodyShape
BodyShape::sample (SynthRng &rng)
{
  BodyShape shape;
  const bool male = rng.chance (0.5);
  const double gender_offset = rng.uniform (0.0, 0.15);
  shape.gender = male ? 1.0 - gender_offset : gender_offset;
  shape.age = ageFromYears (rng.uniform (25.0, 70.0));
  shape.muscle = rng.uniform (0.2, 0.8);
  shape.weight = rng.uniform (0.05, 0.95);
  // MakeHuman's height slider is steep (a young man is 1.36 m at 0, 1.73 m at 0.5, 2.45 m
  // at 1; a woman 1.22, 1.59, 2.3 m): about 0.73 m per unit below the middle, 1.45 m
  // above. A stature offset from MakeHuman's average for the gender (mean 4 cm, sigma
  // 7 cm, clamped to 2.5 sigma) is mapped through the slope of its side.
  const double offset = kStatureShift + kStatureSigma * std::clamp (rng.normal (), -2.5, 2.5);
  shape.height = std::clamp (0.5 + offset / (offset < 0.0 ? 0.73 : 1.45), 0.0, 1.0);
  // Uniform on the simplex: normalised exponential draws (1 - u keeps the log finite).
  double e[3];
  for (double &x : e)
    x = -std::log (1.0 - rng.uniform ());
  const double sum = e[0] + e[1] + e[2];
  if (sum > 0.0)
  {
    shape.african = e[0] / sum;
    shape.asian = e[1] / sum;
    shape.caucasian = 1.0 - shape.african - shape.asian;
  }
  return shape;
}

double
BodyShape::ageFromYears (double years)
{
  if (years < kYearsAtMiddle)
    return (years - kYearsAtZero) / (2.0 * (kYearsAtMiddle - kYearsAtZero));
  return 0.5 + (years - kYearsAtMiddle) / (2.0 * (kYearsAtOne - kYearsAtMiddle));
}

double
BodyShape::ageYears () const
{
  if (age < 0.5)
    return kYearsAtZero + 2.0 * (kYearsAtMiddle - kYearsAtZero) * age;
  return kYearsAtMiddle + 2.0 * (kYearsAtOne - kYearsAtMiddle) * (age - 0.5);
}

std::string
BodyShape::problem () const
{
  const struct
  {
    const char *name;
    double value;
  } values[] = {{"gender", gender}, {"age", age},       {"muscle", muscle},      {"weight", weight},
                {"height", height}, {"african", african}, {"asian", asian}, {"caucasian", caucasian}};
  for (const auto &v : values)
    if (!(v.value >= 0.0 && v.value <= 1.0))
      return std::string ("body shape: ") + v.name + " must be within 0..1, got " + std::to_string (v.value);
  if (age < kMinAge)
    return "body shape: age must be at least " + fixed (kMinAge) +
           " (25 years; MakeHuman's child targets are not shipped), got " + std::to_string (age);
  const double ethnic = african + asian + caucasian;
  if (std::abs (ethnic - 1.0) > 1e-6)
    return "body shape: african + asian + caucasian must be 1, got " + std::to_string (ethnic);
  return {};
}

std::string
BodyShape::describe () const
{
  return "gender=" + fixed (gender) + " age=" + fixed (age) + " (" + fixed (ageYears (), 0) + " y) muscle=" +
         fixed (muscle) + " weight=" + fixed (weight) + " height=" + fixed (height) + " ethnic=" + fixed (african) +
         "/" + fixed (asian) + "/" + fixed (caucasian);
}
}  // namespace agex

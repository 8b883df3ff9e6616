#pragma once
// A person's body shape as MakeHuman's macro variables (doc/synthetic.md, "Body shapes").
#include <string>

namespace agex
{
class SynthRng;

/** \brief MakeHuman 1.1's macro variables, each 0..1 as MakeHuman's sliders hold them.
  *
  * The shape is applied to the MakeHuman mesh by MakeHumanTargets (blended macro targets)
  * through HumanMesh::shaped. The default is MakeHuman's default human (every slider at
  * its middle, the three ethnic groups mixed equally). */
struct BodyShape
{
  /** 0 female, 1 male (MakeHuman blends the female and male targets linearly). */
  double gender = 0.5;
  /** 0 = 1 year, 0.1875 = 11, 0.5 = 25, 1 = 90 years (piecewise linear, MakeHuman's
    * human.getAgeYears). Only the young and old targets ship in ../shared, so a valid
    * shape is at least 25 years old (0.5); see ageFromYears. */
  double age = 0.5;
  /** 0 least, 0.5 average, 1 most muscular. */
  double muscle = 0.5;
  /** 0 lightest (MakeHuman's "50%"), 0.5 average, 1 heaviest ("150%"). */
  double weight = 0.5;
  /** 0 shortest, 0.5 average, 1 tallest for the gender, age, muscle and weight. */
  double height = 0.5;
  /** Ethnic mix (MakeHuman's African, Asian, Caucasian sliders); they sum to 1. */
  double african = 1.0 / 3.0, asian = 1.0 / 3.0, caucasian = 1.0 / 3.0;

  /** The youngest age the shipped targets describe: 25 years (MakeHuman's "young"). */
  static constexpr double kMinAge = 0.5;

  /** \brief Draws an adult (doc/synthetic.md, "Body shapes"): gender female (0-0.15) or
    * male (0.85-1) with equal chance, age 25-70 years uniform, muscle uniform 0.2-0.8,
    * weight uniform 0.05-0.95 (slim to heavy), height such that stature is MakeHuman's
    * average for the gender + 4 cm + 7 cm x z (z standard normal clamped to +-2.5;
    * MakeHuman's height slider moves stature about 0.73 m per unit below the middle and
    * 1.45 m above, so height = 0.5 + offset / 0.73 or 1.45), the ethnic mix uniform on
    * the simplex. Standing heights come out at about 1.45-2.0 m. */
  static BodyShape sample (SynthRng &rng);

  /** MakeHuman's age value for an age in years (1-90). */
  static double ageFromYears (double years);
  /** The age in years (MakeHuman's human.getAgeYears). */
  double ageYears () const;

  /** What is wrong with the shape ("" if nothing): every value finite and in 0..1, age
    * at least kMinAge, the ethnic mix summing to 1 (within 1e-6). */
  std::string problem () const;
  bool valid () const { return problem ().empty (); }
  /** "gender=0.93 age=0.61 (39 y) muscle=... weight=... height=... ethnic=0.2/0.5/0.3" */
  std::string describe () const;
};
}  // namespace agex

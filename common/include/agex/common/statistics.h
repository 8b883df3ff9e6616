#pragma once
// Small measures every evaluation and timing report shares.

#include <Eigen/Core>

#include <chrono>
#include <cstddef>
#include <utility>
#include <vector>

namespace agex
{
/** Milliseconds since start (steady clock). */
double msSince (std::chrono::steady_clock::time_point start);

/** The median (the mean of the two middle values for an even count); NaN when empty. */
double median (std::vector<double> values);

/** \brief Average precision of scored detections, (score, true positive) each, against
  * positives truths: all-point interpolated, as PASCAL VOC since 2010 (precision made
  * monotone from the right, summed over the recall steps). Detections are ranked by score,
  * ties in the order given. 0 when there are no positives. */
double averagePrecision (std::vector<std::pair<double, bool>> scored, std::size_t positives);

/** v as an int clamped to [lo, hi] (NaN: lo), truncated toward zero. Sizes and indices
  * computed from coordinates or intrinsics may lie far beyond an int, and converting such a
  * float to an int is undefined (in practice INT_MIN: a negative index). */
inline int
clampedInt (double v, int lo, int hi)
{
  return v >= lo ? (v <= hi ? static_cast<int> (v) : hi) : lo;
}

/** Degrees between two directions (unit or not); NaN when either is zero or not finite. */
double angleBetweenDeg (const Eigen::Vector3f &a, const Eigen::Vector3f &b);
}  // namespace agex

#pragma once
// Small measures every evaluation and timing report shares.

#include <Eigen/Core>

#include <chrono>
#include <vector>

namespace agex
{
/** Milliseconds since start (steady clock). */
double msSince (std::chrono::steady_clock::time_point start);

/** The median (the mean of the two middle values for an even count); NaN when empty. */
double median (std::vector<double> values);

/** Degrees between two directions (unit or not); NaN when either is zero or not finite. */
double angleBetweenDeg (const Eigen::Vector3f &a, const Eigen::Vector3f &b);
}  // namespace agex

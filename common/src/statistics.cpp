#include <agex/common/statistics.h>

#include <algorithm>
#include <cmath>

namespace agex
{
double
msSince (std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ();
}

double
median (std::vector<double> values)
{
  if (values.empty ())
    return std::nan ("");
  std::sort (values.begin (), values.end ());
  const std::size_t n = values.size ();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double
angleBetweenDeg (const Eigen::Vector3f &a, const Eigen::Vector3f &b)
{
  if (!a.allFinite () || !b.allFinite () || !(a.norm () > 0.f) || !(b.norm () > 0.f))
    return std::nan ("");
  const double c = std::clamp (static_cast<double> (a.normalized ().dot (b.normalized ())), -1.0, 1.0);
  return std::acos (c) * 180.0 / M_PI;
}
}  // namespace agex

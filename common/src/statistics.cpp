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
averagePrecision (std::vector<std::pair<double, bool>> scored, std::size_t positives)
{
  if (positives == 0)
    return 0.0;
  std::stable_sort (scored.begin (), scored.end (), [] (const auto &a, const auto &b) { return a.first > b.first; });
  std::vector<double> precision, recall;
  std::size_t tp = 0;
  for (std::size_t i = 0; i < scored.size (); ++i)
  {
    tp += scored[i].second;
    precision.push_back (static_cast<double> (tp) / (i + 1));
    recall.push_back (static_cast<double> (tp) / positives);
  }
  for (std::size_t i = precision.size (); i-- > 1;)
    precision[i - 1] = std::max (precision[i - 1], precision[i]);
  double ap = 0, previous_recall = 0;
  for (std::size_t i = 0; i < recall.size (); ++i)
  {
    ap += (recall[i] - previous_recall) * precision[i];
    previous_recall = recall[i];
  }
  return ap;
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

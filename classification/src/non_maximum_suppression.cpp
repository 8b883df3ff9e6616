#include <agex/classification/non_maximum_suppression.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

std::vector<std::size_t>
agex::suppressNonMaxima (const std::vector<Eigen::Vector3f> &positions, const std::vector<int> &classes,
                         const std::vector<float> &scores, float radius)
{
  if (positions.size () != classes.size () || positions.size () != scores.size ())
    throw std::invalid_argument ("suppressNonMaxima: positions, classes and scores differ in length");
  std::vector<std::size_t> order;
  order.reserve (scores.size ());
  for (std::size_t i = 0; i < scores.size (); ++i)
    if (std::isfinite (scores[i]) && positions[i].allFinite ())
      order.push_back (i);
  std::stable_sort (order.begin (), order.end (), [&] (std::size_t a, std::size_t b) { return scores[a] > scores[b]; });
  if (!(radius > 0.f))
    return order;
  const float radius_sq = radius * radius;
  std::vector<std::size_t> kept;
  for (const std::size_t i : order)
  {
    const bool suppressed = std::any_of (kept.begin (), kept.end (), [&] (std::size_t k) {
      return classes[k] == classes[i] && (positions[k] - positions[i]).squaredNorm () < radius_sq;
    });
    if (!suppressed)
      kept.push_back (i);
  }
  return kept;
}

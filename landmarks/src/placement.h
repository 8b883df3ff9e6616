#pragma once
// Placing pasted people without overlap, shared by pasted_people.cpp and people_crops.cpp
// (private header).

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace agex
{
namespace detail
{
/** How much a candidate box collides with the boxes already there: the largest share of
  * either box the other covers. */
inline double
collision (const cv::Rect &box, const std::vector<cv::Rect> &taken)
{
  double worst = 0;
  for (const cv::Rect &t : taken)
  {
    const double overlap = (box & t).area ();
    if (overlap > 0)
      worst = std::max (worst, overlap / std::min (box.area (), std::max (1, t.area ())));
  }
  return worst;
}

/** Of 24 places drawn by draw () (each a pair: where the thing goes, the box it then takes),
  * the first that collides with nothing in taken, else the least colliding. */
template <class Draw>
cv::Rect
leastCollidingPlace (Draw draw, const std::vector<cv::Rect> &taken)
{
  cv::Rect best;
  double best_collision = 2.0;
  for (int candidate = 0; candidate < 24 && best_collision > 0; ++candidate)
  {
    const std::pair<cv::Rect, cv::Rect> place = draw ();
    const double hit = collision (place.second, taken);
    if (hit < best_collision)
    {
      best_collision = hit;
      best = place.first;
    }
  }
  return best;
}

/** Item i's place in [0, 1) by the golden ratio: evenly spread, the same in every run. */
inline double
goldenSpread (std::size_t i)
{
  return std::fmod (0.5 + 0.6180339887498949 * static_cast<double> (i), 1.0);
}
} // namespace detail
} // namespace agex

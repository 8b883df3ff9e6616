#pragma once
// cv::Rect <-> dlib::rectangle for the two dlib translation units (private header).

#include <dlib/geometry/rectangle.h>
#include <opencv2/core.hpp>

namespace agex
{
namespace detail
{
inline dlib::rectangle
toDlib (const cv::Rect &r)
{
  return dlib::rectangle (r.x, r.y, r.x + r.width - 1, r.y + r.height - 1);
}

inline cv::Rect
toCv (const dlib::rectangle &r)
{
  return cv::Rect (static_cast<int> (r.left ()), static_cast<int> (r.top ()), static_cast<int> (r.width ()),
                   static_cast<int> (r.height ()));
}
}  // namespace detail
}  // namespace agex

#include <agex/common/pixel_box.h>

#include <algorithm>

namespace agex
{
float
intersectionOverUnion (const PixelBox &a, const PixelBox &b)
{
  const float area_a = std::max (0.f, a.u1 - a.u0) * std::max (0.f, a.v1 - a.v0);
  const float area_b = std::max (0.f, b.u1 - b.u0) * std::max (0.f, b.v1 - b.v0);
  const float overlap = std::max (0.f, std::min (a.u1, b.u1) - std::max (a.u0, b.u0)) *
                        std::max (0.f, std::min (a.v1, b.v1) - std::max (a.v0, b.v0));
  const float united = area_a + area_b - overlap;
  return area_a > 0.f && area_b > 0.f && united > 0.f ? overlap / united : 0.f;
}
}  // namespace agex

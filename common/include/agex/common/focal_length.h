#pragma once
// The focal lengths agex accepts: one range for the frame input, the apps' flags, the Python
// module and the stages that derive sizes (cells, bins, windows) from a focal length.

namespace agex
{
/** Focal lengths agex accepts, pixels. Depth cameras have about 100 to a few thousand; far
  * outside that a frame's metric sizes no longer fit its pixel grid (a 1e-6 px focal length
  * puts neighbouring pixels kilometres apart). */
constexpr double kMinFocalLength = 1e-3;
constexpr double kMaxFocalLength = 1e6;

/** Whether f pixels lies in [kMinFocalLength, kMaxFocalLength] (false for NaN). */
inline bool
saneFocalLength (double f)
{
  return f >= kMinFocalLength && f <= kMaxFocalLength;
}
}  // namespace agex

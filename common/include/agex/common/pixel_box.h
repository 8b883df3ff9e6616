#pragma once
// Axis-aligned boxes in pixels and their overlap: what both detection evaluations (body
// parts in depth frames, people in photos) match with.

namespace agex
{
/** A box in pixels: [u0, u1) x [v0, v1). */
struct PixelBox
{
  float u0 = 0.f, v0 = 0.f, u1 = 0.f, v1 = 0.f;
};

/** Intersection over union of two boxes (0 if either is empty). */
float intersectionOverUnion (const PixelBox &a, const PixelBox &b);
}  // namespace agex

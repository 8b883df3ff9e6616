#pragma once
// Greedy non-maximum suppression of scored, classed 3D candidates: what both detectors
// (AGEX points and sliding windows) use to keep one detection per body part.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace agex
{
/** \brief Greedy per-class non-maximum suppression.
  *
  * Candidates are visited by falling score (ties in input order); a candidate is kept
  * unless an already kept candidate of the same class lies closer than radius (metres,
  * 3D). radius <= 0 keeps everything. Candidates with a non-finite position or score are
  * dropped (they cannot be placed or ranked).
  * \return the indices of the kept candidates, highest score first
  * \throws std::invalid_argument if the three vectors differ in length */
std::vector<std::size_t> suppressNonMaxima (const std::vector<Eigen::Vector3f> &positions,
                                            const std::vector<int> &classes, const std::vector<float> &scores,
                                            float radius);
}  // namespace agex

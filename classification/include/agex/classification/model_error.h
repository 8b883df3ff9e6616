#pragma once
// The error a damaged, foreign or incompatible classifier model raises when it is read.

#include <stdexcept>

namespace agex
{
/** \brief A model file (or model node) that cannot be used: missing, not an agex model,
  * another format version, or damaged. The message names the file (where there is one)
  * and the problem. Declared here so that FragmentDictionary::read and
  * PatchClassifier::load share it; include either header to get it. */
class ModelError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};
}  // namespace agex

#pragma once
// The body parts agex finds: what every stage, from labels to detections, names.

#include <string>

namespace agex
{
enum class BodyPart
{
  Head = 0,
  Hand = 1,
  Foot = 2
};
constexpr int kBodyPartCount = 3;

/** "head", "hand", "foot". */
const char *bodyPartName (BodyPart part);
/** Inverse of bodyPartName; false for an unknown name. */
bool parseBodyPart (const std::string &name, BodyPart &part);
}  // namespace agex

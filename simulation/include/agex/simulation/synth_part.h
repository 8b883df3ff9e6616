#pragma once
// The body parts of synthetic per-pixel part labels (doc/synthetic.md, "Part labels"):
// the value each pixel of a frame's part-label image (labels/<frame>.png) holds.
#include <cstdint>
#include <map>
#include <string>

namespace agex
{
/** A body part as a per-pixel label; left and right are the subject's own. 0 is not a
  * body (the room, nothing, or no valid depth). */
enum class SynthPart : std::uint8_t
{
  None = 0,
  Head = 1,
  Neck = 2,
  Torso = 3,   ///< chest, belly, shoulders
  Pelvis = 4,  ///< hips and buttocks
  LeftUpperArm = 5,
  RightUpperArm = 6,
  LeftForearm = 7,
  RightForearm = 8,
  LeftHand = 9,
  RightHand = 10,
  LeftThigh = 11,
  RightThigh = 12,
  LeftLowerLeg = 13,
  RightLowerLeg = 14,
  LeftFoot = 15,
  RightFoot = 16,
  Unknown = 255  ///< a body surface whose part is not known
};

/** "head", "neck", "torso", "pelvis", "left_upper_arm", ..., "right_foot", "body" (Unknown),
  * "none". */
const char *synthPartName (SynthPart part);

/** Every body part value and its name (None left out): the dataset's "part_labels". */
std::map<int, std::string> synthPartNames ();
}  // namespace agex

#include <agex/simulation/synth_part.h>

namespace agex
{
const char *
synthPartName (SynthPart part)
{
  switch (part)
  {
    case SynthPart::None: return "none";
    case SynthPart::Head: return "head";
    case SynthPart::Neck: return "neck";
    case SynthPart::Torso: return "torso";
    case SynthPart::Pelvis: return "pelvis";
    case SynthPart::LeftUpperArm: return "left_upper_arm";
    case SynthPart::RightUpperArm: return "right_upper_arm";
    case SynthPart::LeftForearm: return "left_forearm";
    case SynthPart::RightForearm: return "right_forearm";
    case SynthPart::LeftHand: return "left_hand";
    case SynthPart::RightHand: return "right_hand";
    case SynthPart::LeftThigh: return "left_thigh";
    case SynthPart::RightThigh: return "right_thigh";
    case SynthPart::LeftLowerLeg: return "left_lower_leg";
    case SynthPart::RightLowerLeg: return "right_lower_leg";
    case SynthPart::LeftFoot: return "left_foot";
    case SynthPart::RightFoot: return "right_foot";
    case SynthPart::Unknown: return "body";
  }
  return "?";
}

std::map<int, std::string>
synthPartNames ()
{
  std::map<int, std::string> names;
  for (int v = static_cast<int> (SynthPart::Head); v <= static_cast<int> (SynthPart::RightFoot); ++v)
    names[v] = synthPartName (static_cast<SynthPart> (v));
  names[static_cast<int> (SynthPart::Unknown)] = synthPartName (SynthPart::Unknown);
  return names;
}
}  // namespace agex

#include <agex/common/body_part.h>

namespace agex
{
const char *
bodyPartName (BodyPart part)
{
  switch (part)
  {
    case BodyPart::Head: return "head";
    case BodyPart::Hand: return "hand";
    case BodyPart::Foot: return "foot";
  }
  return "unknown";
}

bool
parseBodyPart (const std::string &name, BodyPart &part)
{
  for (int i = 0; i < kBodyPartCount; ++i)
    if (name == bodyPartName (static_cast<BodyPart> (i)))
    {
      part = static_cast<BodyPart> (i);
      return true;
    }
  return false;
}
}  // namespace agex

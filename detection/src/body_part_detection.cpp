#include <agex/detection/body_part_detection.h>

#include <nlohmann/json.hpp>

namespace agex
{
nlohmann::json
toJson (const BodyPartDetection &d)
{
  return {{"class", bodyPartName (d.part)},
          {"confidence", d.confidence},
          {"margin", d.margin},
          {"position", {d.position.x (), d.position.y (), d.position.z ()}},
          {"orientation", {d.orientation.x (), d.orientation.y (), d.orientation.z ()}},
          {"pixel", {d.u, d.v}},
          {"rank", d.rank},
          {"mesh", d.mesh},
          {"person", d.person}};
}
}  // namespace agex

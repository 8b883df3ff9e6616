#pragma once
// The per-pixel output of the body-part labelling stage (agex::BodyPartLabeling): a point
// type registered with PCL, so that a label cloud can be drawn, saved as PCD and reused by
// any templated PCL algorithm. See doc/forest.md.

#include <pcl/pcl_macros.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <cstdint>
#include <limits>

namespace agex
{
/** \brief The parts the labelling stage reports. The first three share their numbers with
  * agex::BodyPart (dataset.h), so a label converts to a dataset part by a cast. */
enum LabelPart : std::int32_t
{
  kLabelNone = -1,     ///< not labelled (not evaluated), or a class that is no body part
  kLabelHead = 0,
  kLabelHand = 1,
  kLabelFoot = 2,
  kLabelOtherBody = 3  ///< any body pixel that is none of the above (torso, arms, legs, neck)
};
/** Parts with a probability in BodyPartLabelPoint (head, hand, foot, other body). */
constexpr int kLabelPartCount = 4;

/** "head", "hand", "foot", "other_body"; "none" for kLabelNone or anything else. */
const char *labelPartName (int part);
/** Inverse of labelPartName for the four parts and "none"; false for an unknown name. */
bool parseLabelPart (const char *name, int &part);

/** \brief One pixel of a body-part label cloud.
  *
  * x, y, z       the input point (metres); NaN where the pixel was not labelled
  * label         the winning part (LabelPart): 0 head, 1 hand, 2 foot, 3 other body,
  *               -1 none (not labelled, or the forest's winner is no body part, e.g. PCL's
  *               Background). Named "label" so that PCL's label colour handler draws it.
  * p_head ...    per-part probabilities: the sum of the forest's class probabilities of the
  *               classes mapped to that part (they sum to at most 1; the rest went to
  *               classes that are no body part); NaN where the pixel was not labelled
  */
struct EIGEN_ALIGN16 BodyPartLabelPoint
{
  PCL_ADD_POINT4D;
  std::int32_t label;
  float p_head;
  float p_hand;
  float p_foot;
  float p_other;

  BodyPartLabelPoint () { setUnlabelled (); }

  /** The probability of part (0..3); NaN for any other value. */
  float probability (int part) const
  {
    switch (part)
    {
    case kLabelHead: return p_head;
    case kLabelHand: return p_hand;
    case kLabelFoot: return p_foot;
    case kLabelOtherBody: return p_other;
    default: return std::numeric_limits<float>::quiet_NaN ();
    }
  }
  void setProbability (int part, float p)
  {
    switch (part)
    {
    case kLabelHead: p_head = p; break;
    case kLabelHand: p_hand = p; break;
    case kLabelFoot: p_foot = p; break;
    case kLabelOtherBody: p_other = p; break;
    default: break;
    }
  }
  /** NaN position and probabilities, label -1. */
  void setUnlabelled ()
  {
    const float nan = std::numeric_limits<float>::quiet_NaN ();
    x = y = z = nan;
    data[3] = 1.f;
    label = kLabelNone;
    p_head = p_hand = p_foot = p_other = nan;
  }

  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace agex

POINT_CLOUD_REGISTER_POINT_STRUCT (agex::BodyPartLabelPoint,
  (float, x, x)
  (float, y, y)
  (float, z, z)
  (std::int32_t, label, label)
  (float, p_head, p_head)
  (float, p_hand, p_hand)
  (float, p_foot, p_foot)
  (float, p_other, p_other))

#include <agex/simulation/pose_retarget.h>

#include <cmath>

namespace agex
{
const char *
skeletonSchemeName (SkeletonScheme scheme)
{
  return scheme == SkeletonScheme::CharacterCreator ? "character-creator" : "cmu";
}

JointNameMap
JointNameMap::of (SkeletonScheme scheme)
{
  JointNameMap m;
  m.scheme = scheme;
  if (scheme == SkeletonScheme::CharacterCreator)
  {
    m.root = "CC_Base_Hip";
    m.chest = "CC_Base_Spine02";
    m.neck = "CC_Base_NeckTwist01";
    m.head = "CC_Base_Head";
    for (int s = 0; s < 2; ++s)
    {
      const std::string p = s == 0 ? "CC_Base_L_" : "CC_Base_R_";
      m.eye[s] = p + "Eye";
      m.hip[s] = p + "Thigh";
      m.knee[s] = p + "Calf";
      m.ankle[s] = p + "Foot";
      m.toe[s] = p + "ToeBase";
      m.shoulder[s] = p + "Upperarm";
      m.elbow[s] = p + "Forearm";
      m.wrist[s] = p + "Hand";
      m.hand_end[s] = p + "Mid1";
      m.index_base[s] = p + "Index1";
      m.pinky_base[s] = p + "Pinky1";
      m.leg_chain[s] = {p + "Thigh", p + "Calf", p + "Foot"};
    }
  }
  else
  {
    m.root = "Hips";
    m.chest = "Spine1";
    m.neck = "Neck1";
    m.head = "Head";
    for (int s = 0; s < 2; ++s)
    {
      const std::string p = s == 0 ? "Left" : "Right";
      m.hip[s] = p + "UpLeg";
      m.knee[s] = p + "Leg";
      m.ankle[s] = p + "Foot";
      m.toe[s] = p + "ToeBase";
      m.shoulder[s] = p + "Arm";
      m.elbow[s] = p + "ForeArm";
      m.wrist[s] = p + "Hand";
      m.hand_end[s] = p + "HandIndex1/End Site";
      m.leg_chain[s] = {std::string (s == 0 ? "LHipJoint" : "RHipJoint"), p + "UpLeg", p + "Leg", p + "Foot"};
    }
  }
  return m;
}

SkeletonScheme
PoseRetarget::detect (const BvhMotion &motion)
{
  if (motion.findJoint ("CC_Base_Hip") >= 0)
    return SkeletonScheme::CharacterCreator;
  if (motion.findJoint ("LeftUpLeg") >= 0 && motion.findJoint ("LeftForeArm") >= 0 && motion.findJoint ("Spine1") >= 0)
    return SkeletonScheme::Cmu;
  throw BvhError (motion.path () +
                  ": not a skeleton the pose bank knows (Character Creator CC_Base_* joints, or the CMU "
                  "Hips/LeftUpLeg/Spine1/LeftForeArm names)");
}

PoseRetarget::PoseRetarget (const BvhMotion &motion, double scale)
  : motion_ (&motion), map_ (JointNameMap::of (detect (motion)))
{
  const std::string &path = motion.path ();
  auto require = [&] (const std::string &name, const char *what) {
    const int j = motion.findJoint (name);
    if (j < 0)
      throw BvhError (path + ": no joint '" + name + "' for the " + what + " (" + skeletonSchemeName (map_.scheme) +
                      " skeleton)");
    return j;
  };
  auto optional = [&] (const std::string &name) { return name.empty () ? -1 : motion.findJoint (name); };
  index_.root = require (map_.root, "pelvis");
  index_.chest = require (map_.chest, "chest");
  index_.neck = require (map_.neck, "neck");
  index_.head = require (map_.head, "head");
  for (int s = 0; s < 2; ++s)
  {
    index_.eye[s] = optional (map_.eye[s]);
    index_.hip[s] = require (map_.hip[s], "hip");
    index_.knee[s] = require (map_.knee[s], "knee");
    index_.ankle[s] = require (map_.ankle[s], "ankle");
    index_.toe[s] = require (map_.toe[s], "toe");
    index_.shoulder[s] = require (map_.shoulder[s], "shoulder");
    index_.elbow[s] = require (map_.elbow[s], "elbow");
    index_.wrist[s] = require (map_.wrist[s], "wrist");
    index_.hand_end[s] = require (map_.hand_end[s], "hand's end");
    index_.index_base[s] = optional (map_.index_base[s]);
    index_.pinky_base[s] = optional (map_.pinky_base[s]);
    for (const auto &name : map_.leg_chain[s])
      index_.leg_chain[s].push_back (require (name, "leg"));
  }
  if (index_.eye[0] < 0 || index_.eye[1] < 0)
    index_.eye[0] = index_.eye[1] = -1;
  if (scale > 0)
    scale_ = scale;
  else if (map_.scheme == SkeletonScheme::CharacterCreator)
    scale_ = 0.01;
  else
    scale_ = autoBvhScale (motion);
  if (motion.frameCount () < 1)
    throw BvhError (path + ": the MOTION section has no frames");
  const PoseTargets t = targets (0);
  const double leg = 0.5 * ((t.knee[0] - t.hip[0]).norm () + (t.ankle[0] - t.knee[0]).norm () +
                            (t.knee[1] - t.hip[1]).norm () + (t.ankle[1] - t.knee[1]).norm ());
  if (!(leg > 0.2 && leg < 2.0))
    throw BvhError (path + ": legs of " + std::to_string (leg) + " m at scale " + std::to_string (scale_) +
                    " m/unit; not a human skeleton at this scale");
  leg_ratio_ = PoseSkeleton::legLength () / leg;
}

PoseTargets
PoseRetarget::targets (int frame) const
{
  std::vector<Eigen::Isometry3d> g;
  motion_->pose (frame, scale_, g);
  auto P = [&] (int j) -> Eigen::Vector3d { return g[static_cast<std::size_t> (j)].translation (); };
  PoseTargets t;
  t.root = P (index_.root);
  t.chest = P (index_.chest);
  t.neck = P (index_.neck);
  t.head = P (index_.head);
  if (index_.eye[0] >= 0)
  {
    // Left from the eyes, up along the neck: the head's frame whatever the bones' own frames.
    const Eigen::Vector3d left = (P (index_.eye[0]) - P (index_.eye[1])).normalized ();
    Eigen::Vector3d up = t.head - t.neck;
    up = (up - up.dot (left) * left).normalized ();
    t.head_rotation << left, up, left.cross (up);
    if (!t.head_rotation.allFinite ())
      t.head_rotation.setIdentity ();
  }
  else
    t.head_rotation = g[static_cast<std::size_t> (index_.head)].linear ();
  for (int s = 0; s < 2; ++s)
  {
    t.hip[s] = P (index_.hip[s]);
    t.knee[s] = P (index_.knee[s]);
    t.ankle[s] = P (index_.ankle[s]);
    t.toe[s] = P (index_.toe[s]);
    t.shoulder[s] = P (index_.shoulder[s]);
    t.elbow[s] = P (index_.elbow[s]);
    t.wrist[s] = P (index_.wrist[s]);
    t.hand_end[s] = P (index_.hand_end[s]);
    if (index_.index_base[s] >= 0 && index_.pinky_base[s] >= 0)
      t.palm_across[s] = P (index_.index_base[s]) - P (index_.pinky_base[s]);
    else
      t.palm_across[s] = g[static_cast<std::size_t> (index_.wrist[s])].linear () * Eigen::Vector3d::UnitZ ();
  }
  return t;
}

PoseFrame
PoseRetarget::pose (int frame) const
{
  return PoseSkeleton::solvePose (targets (frame), leg_ratio_);
}

bool
PoseRetarget::zeroedLeg (int frame) const
{
  if (frame < 0 || frame >= motion_->frameCount ())
    throw std::out_of_range (motion_->path () + ": frame " + std::to_string (frame) + " out of range");
  const double *values = motion_->frame (frame);
  auto still = [&] (int side) {
    for (const int j : index_.leg_chain[side])
    {
      const BvhJoint &joint = motion_->joints ()[static_cast<std::size_t> (j)];
      for (std::size_t c = 0; c < joint.channels.size (); ++c)
        if (joint.channels[c] >= BvhChannel::Xrotation && values[joint.first_channel + static_cast<int> (c)] != 0.0)
          return false;
    }
    return true;
  };
  return still (0) != still (1);
}
}  // namespace agex

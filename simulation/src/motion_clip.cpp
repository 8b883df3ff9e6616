// Motion capture clips and the joints bodies hang on.
#include <agex/simulation/motion_clip.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
/** First joint (not an End Site) with one of the names, -1 if none. */
int
findAny (const BvhMotion &motion, const std::vector<std::string> &names)
{
  for (const auto &name : names)
  {
    const int j = motion.findJoint (name);
    if (j >= 0 && !motion.joints ()[j].end_site)
      return j;
  }
  return -1;
}

std::vector<std::string>
sided (const std::vector<std::string> &patterns, const std::string &side)
{
  std::vector<std::string> names;
  for (std::string p : patterns)
  {
    const auto at = p.find ('*');
    if (at != std::string::npos)
      p.replace (at, 1, side);
    names.push_back (p);
  }
  return names;
}

std::string
joinNames (const std::vector<std::string> &names)
{
  std::string s;
  for (const auto &n : names)
    s += (s.empty () ? "" : ", ") + n;
  return s;
}

bool
isDescendant (const BvhMotion &motion, int joint, int ancestor)
{
  for (int j = joint; j >= 0; j = motion.joints ()[j].parent)
    if (j == ancestor)
      return true;
  return false;
}

int
endSiteOf (const BvhMotion &motion, int joint)
{
  for (std::size_t j = 0; j < motion.joints ().size (); ++j)
    if (motion.joints ()[j].parent == joint && motion.joints ()[j].end_site)
      return static_cast<int> (j);
  return -1;
}
}  // namespace

SkeletonMap
SkeletonMap::find (const BvhMotion &motion)
{
  SkeletonMap m;
  const std::string &path = motion.path ();
  auto require = [&] (const std::vector<std::string> &names, const std::string &what) {
    const int j = findAny (motion, names);
    if (j < 0)
      throw BvhError (path + ": no joint for the " + what + " (looked for " + joinNames (names) +
                      "); the synthetic body needs a CMU-style human skeleton");
    return j;
  };
  m.root = 0;
  m.head = require ({"Head"}, "head");
  m.neck = require ({"lowerneck", "Neck", "Neck1"}, "neck");
  m.spine_mid = require ({"Spine", "Chest", "Spine1"}, "middle of the spine");
  m.spine_base = findAny (motion, {"LowerBack", "Spine0"});
  if (m.spine_base < 0)
    m.spine_base = m.root;
  m.head_end = endSiteOf (motion, m.head);

  std::vector<Eigen::Isometry3d> rest;
  motion.pose (-1, 1.0, rest);
  auto P = [&] (int j) { return rest[j].translation (); };

  const char *side_names[2] = {"Left", "Right"};
  for (int s = 0; s < 2; ++s)
  {
    const std::string side = side_names[s];
    const std::string lower = s == 0 ? "left " : "right ";
    m.shoulder[s] = require (sided ({"*Arm", "*UpArm", "*UpperArm", "*Shoulder"}, side), lower + "upper arm");
    m.elbow[s] = require (sided ({"*ForeArm", "*Elbow", "*LowerArm"}, side), lower + "elbow");
    m.wrist[s] = require (sided ({"*Hand", "*Wrist"}, side), lower + "wrist");
    m.hip[s] = require (sided ({"*UpLeg", "*Hip", "*Thigh", "*UpperLeg"}, side), lower + "hip");
    m.knee[s] = require (sided ({"*Leg", "*Knee", "*Shin", "*LowerLeg"}, side), lower + "knee");
    m.ankle[s] = require (sided ({"*Foot", "*Ankle"}, side), lower + "ankle");
    m.toe[s] = findAny (motion, sided ({"*ToeBase", "*Toe", "*Toes"}, side));
    if (m.toe[s] >= 0 && !isDescendant (motion, m.toe[s], m.ankle[s]))
      m.toe[s] = -1;
    const int toe_end = m.toe[s] >= 0 ? endSiteOf (motion, m.toe[s]) : -1;
    m.toe_end[s] = toe_end >= 0 && (P (toe_end) - P (m.toe[s])).norm () > 1e-9 ? toe_end : -1;
    // The hand's end: the descendant of the wrist farthest along the forearm (fingers,
    // not the thumb), if it is away from the wrist at all.
    const Eigen::Vector3d forearm = (P (m.wrist[s]) - P (m.elbow[s])).normalized ();
    double best = 0.0;
    for (std::size_t j = 0; j < motion.joints ().size (); ++j)
      if (static_cast<int> (j) != m.wrist[s] && isDescendant (motion, static_cast<int> (j), m.wrist[s]))
      {
        const double along = (P (static_cast<int> (j)) - P (m.wrist[s])).dot (forearm);
        if (along > best)
        {
          best = along;
          m.hand_end[s] = static_cast<int> (j);
        }
      }
  }
  for (int s = 0; s < 2; ++s)
    if (m.shoulder[s] == m.shoulder[1 - s] || m.hip[s] == m.hip[1 - s])
      throw BvhError (path + ": left and right limbs are the same joints");

  // Rest-pose basis: the subject's left (from the hips), up (root to neck), forward.
  Eigen::Vector3d left = P (m.hip[0]) - P (m.hip[1]);
  Eigen::Vector3d up = P (m.neck) - P (m.root);
  if (left.norm () < 1e-9 || up.norm () < 1e-9)
    throw BvhError (path + ": degenerate rest pose (hips or spine of zero length)");
  left.normalize ();
  up = (up - up.dot (left) * left);
  if (up.norm () < 1e-9)
    throw BvhError (path + ": degenerate rest pose (spine along the hips)");
  up.normalize ();
  m.rest_basis << left, up, left.cross (up);
  return m;
}

MotionClip
MotionClip::load (const std::string &path, double scale)
{
  MotionClip clip;
  clip.motion = BvhMotion::read (path);
  if (clip.motion.frameCount () < 1)
    throw BvhError (path + ": the MOTION section has no frames");
  clip.map = SkeletonMap::find (clip.motion);
  clip.scale_auto = !(scale > 0);
  clip.scale = clip.scale_auto ? autoBvhScale (clip.motion) : scale;
  clip.sequence = std::filesystem::path (path).stem ().string ();
  if (clip.sequence.empty ())
    clip.sequence = "motion";
  return clip;
}
}  // namespace agex

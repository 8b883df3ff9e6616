#pragma once
// BVH motion capture files (Biovision hierarchy): the HIERARCHY (joints, offsets,
// channels in any order, End Sites) and the MOTION (one frame of channel values
// per line), and forward kinematics to global joint poses in metres.
//
// Conventions (those of the CMU BVH conversions and most tools):
//   * Rotation channels are in degrees and compose in the order they are listed:
//     "CHANNELS 3 Zrotation Xrotation Yrotation" gives R = Rz * Rx * Ry, applied to
//     column vectors in the joint's parent frame.
//   * A joint's local translation is its OFFSET; a position channel, where a joint
//     has one (usually the root), replaces that component of the OFFSET.
//   * The rest pose is the pose with every channel zero.
// Offsets and position channels are in file units; forward kinematics multiplies
// them by a scale (metres per file unit), see autoBvhScale.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <stdexcept>
#include <string>
#include <vector>

namespace agex
{
/** A BVH problem; the message names the file (and line) and what is wrong. */
class BvhError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

enum class BvhChannel
{
  Xposition,
  Yposition,
  Zposition,
  Xrotation,
  Yrotation,
  Zrotation
};

/** "Xposition", ..., "Zrotation". */
const char *bvhChannelName (BvhChannel channel);

struct BvhJoint
{
  std::string name;                 ///< End Sites are named "<parent>/End Site"
  int parent = -1;                  ///< index into BvhMotion::joints(), -1 for a root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero ();  ///< file units, in the parent's frame
  std::vector<BvhChannel> channels;  ///< in file order
  int first_channel = 0;            ///< column of the first channel in a frame row
  bool end_site = false;
  int line = 0;                     ///< line of the JOINT / ROOT / End Site keyword
};

/** Metres per CMU BVH unit (0.0254 / 0.45): offsets and root positions of the
  * original CMU conversions (e.g. cmu_02_01.bvh) times this are metres. */
constexpr double kCmuBvhUnit = 0.056444;

class BvhMotion
{
public:
  /** \brief Reads and validates a BVH file. \throws BvhError naming path:line */
  static BvhMotion read (const std::string &path);
  /** \brief Parses BVH text; name is used in error messages. \throws BvhError */
  static BvhMotion parse (const std::string &text, const std::string &name);

  const std::string &path () const { return path_; }
  /** Joints in file order: every parent comes before its children. */
  const std::vector<BvhJoint> &joints () const { return joints_; }
  int channelCount () const { return channel_count_; }
  int frameCount () const { return frame_count_; }
  double frameTime () const { return frame_time_; }
  /** Channel values of a frame (channelCount() of them). */
  const double *frame (int index) const { return values_.data () + static_cast<std::size_t> (index) * channel_count_; }

  /** Index of the joint with this name (exact, then case-insensitive), -1 if none. */
  int findJoint (const std::string &name) const;

  /** \brief Global pose of every joint at a frame (-1 = the rest pose): rotation and
    * translation in the world frame of the file, translations in file units times scale.
    * \throws std::out_of_range for a bad frame index */
  void pose (int frame, double scale, std::vector<Eigen::Isometry3d> &globals) const;

  /** Vertical (Y) extent of the rest pose over all joints and End Sites, file units. */
  double restHeight () const;

private:
  std::string path_;
  std::vector<BvhJoint> joints_;
  int channel_count_ = 0;
  int frame_count_ = 0;
  double frame_time_ = 0.0;
  std::vector<double> values_;
};

/** \brief Metres per file unit guessed from the rest-pose height h (file units):
  * h <= 3: metres (1); h <= 60: CMU units (kCmuBvhUnit); h <= 300: centimetres
  * (0.01); else millimetres (0.001). \throws BvhError if the skeleton has no height */
double autoBvhScale (const BvhMotion &motion);
}  // namespace agex

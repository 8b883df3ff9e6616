#pragma once
// A bank of body poses for synthetic people (doc/synthetic.md, "Pose bank"): poses of
// motion capture files and directories (any skeleton PoseRetarget knows) and procedural
// poses, all carried over to the pose skeleton, stood on the floor, thinned by furthest
// point sampling (Shotton et al. 2011: the distance of two poses is the largest distance
// of a joint, root-relative with the facing removed), with a report of their spread.

#include <agex/simulation/pose_skeleton.h>
#include <agex/simulation/synthetic_scene.h>

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace agex
{
/** Where a bank's poses came from and how many were kept. */
struct PoseSource
{
  std::string name;   ///< directory or file stem, or "procedural"
  int raw = 0;        ///< poses read
  int dropped = 0;    ///< refused (a zeroed leg, a procedural pose past a limit)
  int kept = 0;       ///< in the bank after thinning
};

/** Hand positions of a source's poses relative to the pelvis, facing removed, metres on
  * the 1.72 m pose skeleton: x outward from the body's midline (each hand on its own side),
  * y up, z forward. */
struct HandSpread
{
  std::string source;
  int hands = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero (), sd = Eigen::Vector3d::Zero ();
  double above_head = 0;  ///< fraction of hands above the top of the head joint
  double forward = 0;     ///< ... more than 0.35 m in front of the pelvis (reaching, pointing)
  double behind = 0;      ///< ... more than 0.10 m behind it
  double across = 0;      ///< ... past the midline to the other side
};

class PoseBank
{
public:
  /** At most this many poses are read in all (each pose holds 22 rotations). */
  static constexpr int kMaxPoses = 200000;
  /** At most this many BVH files are read from one directory. */
  static constexpr int kMaxFiles = 10000;

  /** \brief Adds every frame of a BVH file (frames with a zeroed leg dropped).
    * \throws BvhError naming the file; std::length_error past kMaxPoses */
  void addFile (const std::string &path, const std::string &source = "");
  /** \brief Adds every *.bvh file of a directory (sorted by name) as one source.
    * \throws BvhError naming a bad file or a directory without BVH files */
  void addDirectory (const std::string &directory);
  /** \brief Adds count procedural poses drawn from the seed (ProceduralPoses::generate). */
  void addProcedural (int count, std::uint64_t seed);
  /** Adds poses under a source name (stood on the floor as the others). */
  void addPoses (const std::string &source, const std::vector<PoseFrame> &poses);

  /** \brief Keeps poses farther than `metres` from every kept one (furthest point
    * sampling on the joints); 0 keeps all. \throws std::invalid_argument for < 0 or NaN */
  void thin (double metres);

  int size () const { return static_cast<int> (poses_.size ()); }
  const std::vector<PoseFrame> &poses () const { return poses_; }
  /** Source index (into sources()) of each pose. */
  const std::vector<int> &poseSources () const { return pose_source_; }
  const std::vector<PoseSource> &sources () const { return sources_; }

  /** \brief All poses as one clip on the pose skeleton (frame i = pose i).
    * \throws BvhError if the bank is empty */
  MotionClip clip (const std::string &name = "pose_bank") const;

  /** Hand spread per source, and of all ("all") last. */
  std::vector<HandSpread> handSpread () const;
  /** A front and a top view of the hands (a dot per hand, a colour per source) over the
    * T-pose skeleton (BGR); the caller writes it. */
  cv::Mat spreadImage () const;

  /** Joint positions of a pose as the thinning compares them: root-relative, the pelvis
    * turned to face +Z. */
  static std::vector<Eigen::Vector3d> comparable (const PoseFrame &pose);
  /** Largest distance of a joint between two comparable poses. */
  static double distance (const std::vector<Eigen::Vector3d> &a, const std::vector<Eigen::Vector3d> &b);
  /** \brief Furthest point sampling: starts from item 0, adds the item farthest from
    * those kept while that distance exceeds `threshold`; returns the kept indices, sorted. */
  static std::vector<int> furthestPointSample (const std::vector<std::vector<Eigen::Vector3d>> &items,
                                               double threshold);

private:
  int sourceIndex (const std::string &name);
  void push (int source, PoseFrame pose);

  std::vector<PoseFrame> poses_;
  std::vector<int> pose_source_;
  std::vector<PoseSource> sources_;
};

/** \brief The pose bank a generator's options ask for: their motion files, pose
  * directories and procedural poses (seeded with options.seed), thinned by thin_poses.
  * \throws BvhError naming a bad file, std::invalid_argument if no pose is left */
PoseBank poseBankOf (const SynthOptions &options);
}  // namespace agex

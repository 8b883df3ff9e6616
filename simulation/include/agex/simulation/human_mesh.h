#pragma once
// The CC0 MakeHuman body (../shared/data/makehuman: base.obj, default.mhskel,
// default_weights.mhw) as a skinned body for synthetic frames: the `body` group of the
// base mesh, its 163-bone skeleton and the skin weights, posed by a CMU motion capture
// skeleton (doc/synthetic.md, "Mesh bodies").
#include <agex/simulation/body_shape.h>
#include <agex/simulation/synth_part.h>

#include <Eigen/Core>

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace agex
{
/** A MakeHuman asset file that cannot be used; what() names the file and the problem. */
class HumanMeshError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

class MakeHumanTargets;

class HumanMesh
{
public:
  /** What a vertex belongs to: the parts whose tips are labelled, and the rest. */
  enum Part : int
  {
    Trunk = 0,  ///< torso, neck, shoulders and hips
    Head = 1,
    LeftHand = 2,
    RightHand = 3,
    LeftFoot = 4,
    RightFoot = 5,
    LeftArm = 6,  ///< upper arm and forearm
    RightArm = 7,
    LeftLeg = 8,  ///< thigh and shin
    RightLeg = 9
  };
  static constexpr int kParts = 10;

  struct Bone
  {
    std::string name;
    int parent = -1;  ///< index into bones(), -1 for the root
    Eigen::Vector3d head = Eigen::Vector3d::Zero (), tail = Eigen::Vector3d::Zero ();  ///< rest pose, metres
  };
  struct Influence
  {
    int bone = 0;
    double weight = 0.0;  ///< a vertex's weights sum to 1
  };

  /** \brief Reads base.obj, default.mhskel and default_weights.mhw from a directory.
    * \throws HumanMeshError naming the file and what is wrong with it */
  static HumanMesh load (const std::string &directory);
  /** \brief The same body shaped by MakeHuman's macro targets of the directory (reads
    * them each call; to shape many bodies, load once and call shaped).
    * \throws HumanMeshError naming a bad file, or for an invalid shape */
  static HumanMesh load (const std::string &directory, const BodyShape &shape);

  /** \brief This body with a shape: the targets' blended offsets are added to every
    * vertex of base.obj (unshaped, whatever this body's shape), then the `body` group's
    * vertices, the skeleton (each joint the mean of its helper vertices), the tips and
    * the height are recomputed. Faces, weights, parts and labels stay.
    * \throws HumanMeshError for an invalid shape or targets of another mesh */
  HumanMesh shaped (const MakeHumanTargets &targets, const BodyShape &shape) const;
  /** Whether the body was shaped (shaped()); load (directory) gives base.obj as it is,
    * which is not MakeHuman's default human (that one blends the ethnic targets too). */
  bool isShaped () const { return shaped_; }
  /** The shape given to shaped(); meaningless unless isShaped(). */
  const BodyShape &shape () const { return shape_; }
  /** Vertices of base.obj, all groups (targets index these). */
  std::size_t baseVertexCount () const { return base_vertices_.size (); }

  /** Rest-pose vertices of the `body` group in metres: +X the body's left, +Y up, +Z
    * forward (MakeHuman's frame, decimetres in the file). */
  const std::vector<Eigen::Vector3d> &vertices () const { return vertices_; }
  /** The `body` group's faces, quads split in two. */
  const std::vector<Eigen::Vector3i> &triangles () const { return triangles_; }
  /** Bones, every parent before its children. */
  const std::vector<Bone> &bones () const { return bones_; }
  /** Index of a bone by name, -1 if there is none. */
  int bone (const std::string &name) const;
  /** Skin weights per vertex. */
  const std::vector<std::vector<Influence>> &influences () const { return influences_; }
  /** The part of each vertex (by the bone with the largest weight). */
  const std::vector<Part> &parts () const { return parts_; }
  /** The part of each triangle (that of most of its vertices). */
  const std::vector<Part> &triangleParts () const { return triangle_parts_; }
  /** The per-pixel label part of each bone, by the subtree it lies in: head (and face),
    * neck, upper arm, forearm, hand (and fingers), thigh, lower leg, foot (and toes);
    * pelvis for root, pelvis.L/R and spine05; torso for the rest (spine, clavicles,
    * shoulders, breasts). */
  const std::vector<SynthPart> &boneLabels () const { return bone_labels_; }
  /** The per-pixel label part of each triangle: that of the bone with the largest skin
    * weight summed over the triangle's three corners (ties: the first bone). */
  const std::vector<SynthPart> &triangleLabels () const { return triangle_labels_; }
  /** Tip vertices of the labelled parts, indexed by Part (-1 for the others): the top
    * of the head, the tip of each middle finger, the front of each foot. */
  const std::array<int, kParts> &tipVertices () const { return tips_; }
  /** Rest-pose height, top of the head to the soles, metres (at least 0.5). */
  double height () const { return height_; }

private:
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<Bone> bones_;
  std::vector<std::vector<Influence>> influences_;
  std::vector<Part> parts_, triangle_parts_;
  std::vector<SynthPart> bone_labels_, triangle_labels_;
  std::array<int, kParts> tips_{};
  double height_ = 0.0;
  // What shaped() needs: base.obj's vertices (metres, unshaped), each body vertex's
  // index among them, and the helper vertices of each bone's head (2b) and tail (2b + 1).
  std::string directory_;
  std::vector<Eigen::Vector3d> base_vertices_;
  std::vector<int> body_vertex_source_;
  std::vector<std::vector<int>> joint_vertices_;
  bool shaped_ = false;
  BodyShape shape_;
};
}  // namespace agex

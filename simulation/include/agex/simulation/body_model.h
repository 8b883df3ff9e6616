#pragma once
// Bodies posed by a clip: the capsule-and-ellipsoid body (buildBody) and the MakeHuman mesh
// body (buildMeshBody, mesh_body.cpp), as scene primitives with their tips and bases
// (doc/synthetic.md, "Body model" and "Mesh bodies").
#include <agex/simulation/motion_clip.h>
#include <agex/simulation/scene_primitives.h>
#include <agex/simulation/synth_rng.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace agex
{
/** Per-subject body shape; every length of the body model is in metres. */
struct BodyParams
{
  double height_scale = 1.0;  ///< multiplies the skeleton (and every size below)
  double girth = 1.0;         ///< multiplies torso and limb radii
  double head_scale = 1.0;    ///< multiplies the head ellipsoid
  double arm_girth = 1.0;     ///< extra factor on arm radii
  double leg_girth = 1.0;     ///< extra factor on leg radii
  double torso_depth = 1.0;   ///< front-back size of the torso
  double reflectivity = 0.7;  ///< clothes and skin, 0..1
  /** Clothes on mesh bodies (buildMeshBody), metres each part's surface moves out along its
    * normal: real people's sleeves, trousers and shoes make arms, legs and feet wider than
    * the bare MakeHuman mesh (doc/results.md, "Synthetic hands and feet are thinner than
    * real ones"). 0: bare (the default). */
  double clothes_top = 0.0;     ///< trunk and arms
  double clothes_bottom = 0.0;  ///< legs
  double shoes = 0.0;           ///< feet (a shoe's sole and upper)
  double hands = 0.0;           ///< hands: what a Kinect sees of curled fingers is a blob
  double hair = 0.0;            ///< on the top of the head, fading out to its middle

  /** Draws a subject's clothes: top 0.3-2.5 cm, bottom 0.3-2.5 cm, shoes 0.8-2.5 cm,
    * hands 0.2-1 cm, hair 0-3 cm. */
  void dress (SynthRng &rng);
  bool dressed () const { return clothes_top > 0 || clothes_bottom > 0 || shoes > 0 || hands > 0 || hair > 0; }

  /** Draws a subject: height 0.92-1.08, girth 0.85-1.25, head 0.93-1.07, arms and legs
    * 0.9-1.12, torso depth 0.9-1.2, reflectivity 0.45-0.9. */
  static BodyParams random (SynthRng &rng);
  /** "height_scale=1.02 girth=0.93 ..." */
  std::string describe () const;
};

/** A posed body in the clip's world frame (metres, Y up). */
struct BodyModel
{
  std::vector<SynthPrimitive> primitives;  ///< all SynthObject::Person
  /** Tip and base of the head (0), the hands (1: left, 2: right) and feet (3: left,
    * 4: right); tips on the body surface. */
  Eigen::Vector3d tip[5], base[5];
  /** Per tip: the primitives of its part (head ellipsoid; hand; foot and toes) and the
    * depth tolerance of its visibility test: the part's radius + 3 cm, since the
    * surface seen near a tip on the part's silhouette is up to a radius in front of it. */
  std::vector<int> tip_primitives[5];
  double tip_tolerance[5] = {0, 0, 0, 0, 0};
  /** Middle of the torso (between the root and the neck). */
  Eigen::Vector3d centre = Eigen::Vector3d::Zero ();
  /** Lowest and highest point of the body (Y). */
  double lowest = 0.0, highest = 0.0;
  /** The same body after a rigid transform. */
  BodyModel transformed (const Eigen::Isometry3d &transform) const;
};

/** \brief Poses the body model on frame `frame` of a clip (-1 = rest pose). */
BodyModel buildBody (const MotionClip &clip, int frame, const BodyParams &params);

class HumanMesh;

/** \brief Poses the MakeHuman mesh body on frame `frame` of a clip (-1 = rest pose):
  * the mesh is scaled to the clip's rest height times params.height_scale, shaped by
  * the other params (a shaped mesh, HumanMesh::isShaped, keeps its own size and girth
  * instead: only params.reflectivity is used, and the clip's motion is scaled to the
  * mesh's height; doc/synthetic.md, "Body shapes"), and each bone follows the motion capture segment it lies on
  * (rotation of the segment's joint, then turned so the bone points where the segment
  * does; doc/synthetic.md). One mesh primitive per HumanMesh::Part, in its order
  * (trunk, head, hands, feet, arms, legs); tips are mesh vertices (top of the head, middle finger tips,
  * toe fronts), bases the neck, wrist and ankle joints. */
BodyModel buildMeshBody (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh);

/** Heads of the mesh's bones (indexed like mesh.bones()) posed as buildMeshBody poses
  * them: the posed skeleton. */
std::vector<Eigen::Vector3d> meshBoneHeads (const MotionClip &clip, int frame, const BodyParams &params,
                                            const HumanMesh &mesh);

/** Lowest point (Y) of the posed mesh body's feet and a sample of its other vertices:
  * what the floor is placed by, without building the whole body (dressed: each vertex
  * lowered by its clothes' thickness). */
double meshBodyLowest (const MotionClip &clip, int frame, const BodyParams &params, const HumanMesh &mesh);

/** Height of the body model in the clip's rest pose (head top to sole), metres. */
double restStandingHeight (const MotionClip &clip, const BodyParams &params = BodyParams ());
}  // namespace agex

// The pose bank (doc/synthetic.md, "Pose bank"): Character Creator and CMU (Hahne)
// skeletons carried over to the pose skeleton give plausible people (head above the
// hips, hands within an arm of the shoulders, left on the left, standing height, feet at
// the bottom, also as a posed MakeHuman mesh); the broken legs of 111_02 are dropped;
// procedural poses keep to their joint limits and do what their names say; furthest
// point sampling keeps the known points; bad inputs are refused.

#include "test_support.h"

#include <agex/simulation/human_mesh.h>
#include <agex/simulation/pose_bank.h>
#include <agex/simulation/pose_retarget.h>
#include <agex/simulation/procedural_poses.h>

#include <cmath>

namespace
{
using namespace agex_test;
using agex::PoseSkeleton;

#define AGEX_REQUIRE_MOCAP(path) AGEX_REQUIRE_SHARED_FILE (path, "the CMU motion capture (../shared/data/mocap)")

constexpr double kArm = 0.29 + 0.26;

/** Checks one pose as a person: returns what is wrong, empty if nothing. */
std::string
implausible (const agex::PoseFrame &pose)
{
  const std::vector<Eigen::Vector3d> p = agex::PoseBank::comparable (pose);
  std::ostringstream out;
  if (!(p[PoseSkeleton::Head].y () > p[PoseSkeleton::Hips].y () + 0.2))
    out << "head not above the hips; ";
  for (int s = 0; s < 2; ++s)
  {
    const int arm = s == 0 ? PoseSkeleton::LeftArm : PoseSkeleton::RightArm;
    if ((p[arm + 2] - p[arm]).norm () > kArm + 0.01)
      out << "wrist " << s << " farther than an arm from its shoulder; ";
  }
  // Facing removed: the subject's left is +X.
  if (!(p[PoseSkeleton::LeftUpLeg].x () > p[PoseSkeleton::RightUpLeg].x ()))
    out << "left hip not on the left; ";
  if (!(p[PoseSkeleton::LeftArm].x () > p[PoseSkeleton::RightArm].x ()))
    out << "left shoulder not on the left; ";
  return out.str ();
}

void
expectPlausibleSource (const std::string &path, double min_standing)
{
  agex::PoseBank bank;
  bank.addFile (path);
  ASSERT_GT (bank.size (), 0) << path;
  int standing = 0;
  for (int i = 0; i < bank.size (); ++i)
  {
    const std::string problem = implausible (bank.poses ()[static_cast<std::size_t> (i)]);
    EXPECT_TRUE (problem.empty ()) << path << " pose " << i << ": " << problem;
    const std::vector<Eigen::Vector3d> p = PoseSkeleton::positions (bank.poses ()[static_cast<std::size_t> (i)]);
    // Stood on the floor: the lowest surface at 0, a standing head 1.4-1.6 m up.
    if (p[PoseSkeleton::Head].y () > 1.4)
    {
      ++standing;
      EXPECT_LT (p[PoseSkeleton::Head].y (), 1.6) << path << " pose " << i;
      EXPECT_LT (std::min (p[PoseSkeleton::LeftFoot].y (), p[PoseSkeleton::RightFoot].y ()), 0.25) << path << " pose " << i;
    }
  }
  EXPECT_GE (standing, min_standing * bank.size ()) << path;

  // The bank's clip poses the capsule body: height of the pose skeleton, feet at the bottom.
  const agex::MotionClip clip = bank.clip ();
  EXPECT_NEAR (agex::restStandingHeight (clip), 1.80, 0.1);
  const agex::BodyModel body = agex::buildBody (clip, 0, agex::BodyParams ());
  EXPECT_GT (body.tip[0].y (), body.centre.y ());
  EXPECT_LT (body.lowest, 0.15);
}

TEST (PoseBank, CharacterCreatorSkeletonGivesPlausiblePeople)
{
  const std::string walk = sharedData ("mocap/cmu_cc/002_01.bvh");
  AGEX_REQUIRE_MOCAP (walk);
  const agex::BvhMotion motion = agex::BvhMotion::read (walk);
  const agex::PoseRetarget retarget (motion);
  EXPECT_EQ (retarget.scheme (), agex::SkeletonScheme::CharacterCreator);
  EXPECT_DOUBLE_EQ (retarget.scale (), 0.01);  // centimetres
  // Source landmarks in metres: a walking adult's head 1.4-1.9 m above the feet.
  const agex::PoseTargets t = retarget.targets (motion.frameCount () / 2);
  EXPECT_NEAR (t.head.y () - std::min (t.ankle[0].y (), t.ankle[1].y ()), 1.55, 0.2);
  expectPlausibleSource (walk, 0.95);
}

TEST (PoseBank, CmuSkeletonGivesPlausiblePeopleAndDropsZeroedLegs)
{
  const std::string poses = sharedData ("mocap/cmu_poses/13_04.bvh");
  AGEX_REQUIRE_MOCAP (poses);
  const agex::BvhMotion motion = agex::BvhMotion::read (poses);
  EXPECT_EQ (agex::PoseRetarget (motion).scheme (), agex::SkeletonScheme::Cmu);
  expectPlausibleSource (poses, 0.0);  // sitting on a stepstool
  expectPlausibleSource (sharedData ("mocap/cmu_02_01.bvh"), 0.95);

  const std::string broken = sharedData ("mocap/cmu_poses/111_02.bvh");
  AGEX_REQUIRE_MOCAP (broken);
  agex::PoseBank bank;
  bank.addFile (broken);
  EXPECT_EQ (bank.size (), 0);
  ASSERT_EQ (bank.sources ().size (), 1u);
  EXPECT_GT (bank.sources ()[0].dropped, 0);
  EXPECT_EQ (bank.sources ()[0].dropped, bank.sources ()[0].raw);
}

TEST (PoseBank, PosedMeshHasTheSubjectsHeightAndHandsAtTheArmsEnds)
{
  const std::string walk = sharedData ("mocap/cmu_cc/002_01.bvh");
  AGEX_REQUIRE_MOCAP (walk);
  AGEX_REQUIRE_SHARED_FILE (sharedData ("makehuman/default_weights.mhw"), "the MakeHuman body mesh");
  agex::PoseBank bank;
  bank.addFile (walk);
  bank.addProcedural (11, 5);  // one of each arm pose
  const agex::MotionClip clip = bank.clip ();
  const agex::HumanMesh mesh = agex::HumanMesh::load (sharedData ("makehuman"));
  for (const int frame : {-1, 10, bank.size () - 6})
  {
    const agex::BodyModel body = agex::buildMeshBody (clip, frame, agex::BodyParams (), mesh);
    const std::vector<Eigen::Vector3d> bones = agex::meshBoneHeads (clip, frame, agex::BodyParams (), mesh);
    const Eigen::Vector3d shoulder_l = bones[static_cast<std::size_t> (mesh.bone ("upperarm01.L"))];
    const Eigen::Vector3d shoulder_r = bones[static_cast<std::size_t> (mesh.bone ("upperarm01.R"))];
    if (frame <= 10)
    {
      // Standing: the mesh as tall as the skeleton.
      EXPECT_NEAR (body.highest - body.lowest, 1.80, 0.12) << frame;
    }
    // Hands (finger tips) within an arm and a hand of the shoulders, feet at the bottom.
    EXPECT_LT ((body.tip[1] - shoulder_l).norm (), 0.8) << frame;
    EXPECT_LT ((body.tip[2] - shoulder_r).norm (), 0.8) << frame;
    EXPECT_LT (std::min (body.tip[3].y (), body.tip[4].y ()), body.lowest + 0.25) << frame;
    EXPECT_GT (body.tip[0].y (), body.centre.y ()) << frame;
  }
  // The rest pose is symmetric: the left hand mirrors the right.
  const agex::BodyModel rest = agex::buildMeshBody (clip, -1, agex::BodyParams (), mesh);
  EXPECT_NEAR (rest.tip[1].y (), rest.tip[2].y (), 0.01);
  EXPECT_NEAR (rest.tip[1].x () - rest.centre.x (), rest.centre.x () - rest.tip[2].x (), 0.02);
}

TEST (ProceduralPoses, KeepToTheJointLimitsAndDoWhatTheirNamesSay)
{
  const auto poses = agex::ProceduralPoses::generate (440, 11);
  EXPECT_GE (poses.size (), 400u);  // few draws fail their limits 20 times
  std::map<agex::ArmPose, int> seen;
  for (const auto &pose : poses)
  {
    const auto broken = agex::ProceduralPoses::violations (agex::ProceduralPoses::measure (pose.frame));
    EXPECT_TRUE (broken.empty ()) << agex::armPoseName (pose.arms) << ": " << (broken.empty () ? "" : broken[0]);
    EXPECT_TRUE (implausible (pose.frame).empty ()) << agex::armPoseName (pose.arms);
    ++seen[pose.arms];
    const std::vector<Eigen::Vector3d> p = PoseSkeleton::positions (pose.frame);
    const Eigen::Matrix3d pelvis = pose.frame.local[0];
    const Eigen::Vector3d root = p[PoseSkeleton::Hips], forward = pelvis.col (2);
    const Eigen::Vector3d lw = p[PoseSkeleton::LeftHand], rw = p[PoseSkeleton::RightHand];
    const double head = p[PoseSkeleton::Head].y ();
    auto rel = [&] (const Eigen::Vector3d &w) -> Eigen::Vector3d { return pelvis.transpose () * (w - root); };
    switch (pose.arms)
    {
      case agex::ArmPose::HandsOnHips:
      {
        // At least one wrist at the side of the pelvis.
        const double l = (rel (lw) - Eigen::Vector3d (0.16, 0.05, 0)).norm ();
        const double r = (rel (rw) - Eigen::Vector3d (-0.16, 0.05, 0)).norm ();
        EXPECT_LT (std::min (l, r), 0.1);
        break;
      }
      case agex::ArmPose::BothArmsRaised:
        EXPECT_GT (lw.y (), head);
        EXPECT_GT (rw.y (), head);
        break;
      case agex::ArmPose::OneArmRaised: EXPECT_GT (std::max (lw.y (), rw.y ()), head); break;
      case agex::ArmPose::PointingForward:
      {
        const Eigen::Vector3d fore = (rw - p[PoseSkeleton::RightForeArm]).normalized ();
        EXPECT_GT (fore.dot (forward), 0.85);
        break;
      }
      case agex::ArmPose::CrossedArms:
        EXPECT_LT (rel (lw).x (), 0.0);
        EXPECT_GT (rel (rw).x (), 0.0);
        break;
      case agex::ArmPose::HandsBehindBack:
        EXPECT_LT (rel (lw).z (), -0.08);
        EXPECT_LT (rel (rw).z (), -0.08);
        break;
      case agex::ArmPose::HandNearFace:
        EXPECT_LT (std::min ((lw - p[PoseSkeleton::Head]).norm (), (rw - p[PoseSkeleton::Head]).norm ()), 0.25);
        break;
      default: break;
    }
  }
  EXPECT_EQ (seen.size (), static_cast<std::size_t> (agex::ArmPose::kCount));
  // Deterministic from the seed.
  const auto again = agex::ProceduralPoses::generate (20, 11);
  for (std::size_t i = 0; i < again.size (); ++i)
    EXPECT_TRUE (again[i].frame.local[PoseSkeleton::LeftArm].isApprox (poses[i].frame.local[PoseSkeleton::LeftArm]));
}

TEST (PoseBank, FurthestPointSamplingKeepsTheFarthestPoints)
{
  auto point = [] (double x) { return std::vector<Eigen::Vector3d>{Eigen::Vector3d (x, 0, 0)}; };
  // From 0: 1.0 is farthest, then 0.2 (0.2 from 0); 0.1 is within 0.15 of a kept one.
  const std::vector<int> kept = agex::PoseBank::furthestPointSample ({point (0), point (0.1), point (0.2), point (1.0)}, 0.15);
  EXPECT_EQ (kept, (std::vector<int>{0, 2, 3}));
  EXPECT_EQ (agex::PoseBank::furthestPointSample ({point (0), point (0.1), point (0.2), point (1.0)}, 0.0).size (), 4u);
  EXPECT_TRUE (agex::PoseBank::furthestPointSample ({}, 0.1).empty ());

  // Copies of poses thin to one each; turned copies too (facing is removed).
  agex::PoseBank bank;
  const auto made = agex::ProceduralPoses::generate (2, 3);
  std::vector<agex::PoseFrame> copies;
  for (int k = 0; k < 5; ++k)
    for (const auto &m : made)
    {
      agex::PoseFrame f = m.frame;
      f.local[0] = Eigen::AngleAxisd (0.7 * k, Eigen::Vector3d::UnitY ()).toRotationMatrix () * f.local[0];
      copies.push_back (f);
    }
  bank.addPoses ("copies", copies);
  EXPECT_EQ (bank.size (), 10);
  bank.thin (0.01);
  EXPECT_EQ (bank.size (), 2);
  EXPECT_EQ (bank.sources ()[0].raw, 10);
  EXPECT_EQ (bank.sources ()[0].kept, 2);
}

TEST (PoseBank, RefusesBadInputs)
{
  agex::PoseBank bank;
  EXPECT_THROW (bank.thin (-0.1), std::invalid_argument);
  EXPECT_THROW (bank.thin (std::nan ("")), std::invalid_argument);
  EXPECT_THROW (agex::ProceduralPoses::generate (-1, 1), std::invalid_argument);
  EXPECT_THROW (agex::ProceduralPoses::generate (100001, 1), std::invalid_argument);
  EXPECT_THROW (bank.clip (), agex::BvhError);
  TempDir dir;
  EXPECT_THROW (bank.addDirectory (dir.path ().string ()), agex::BvhError);
  EXPECT_THROW (bank.addDirectory ((dir.path () / "missing").string ()), agex::BvhError);
  // A skeleton of no known scheme.
  const std::string odd = (dir.path () / "odd.bvh").string ();
  writeAll (odd, "HIERARCHY\nROOT Base\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n JOINT Arm\n {\n"
                 "  OFFSET 0 1 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\n"
                 "MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0\n");
  try
  {
    bank.addFile (odd);
    ADD_FAILURE () << "an unknown skeleton was accepted";
  }
  catch (const agex::BvhError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("odd.bvh"), std::string::npos) << e.what ();
  }
  EXPECT_EQ (bank.size (), 0);
}
TEST (PoseBank, GeneratorDrawsFromTheBankWithPeopleOnTheFloor)
{
  agex::SynthOptions options;
  options.procedural_poses = 22;
  options.thin_poses = 0.02;
  options.sensor = agex::SynthSensor::Kinect;
  options.seed = 4;
  const agex::SynthGenerator generator (options);
  ASSERT_EQ (generator.clips ().size (), 1u);
  const int poses = generator.clips ()[0].motion.frameCount ();
  EXPECT_GE (poses, 18);
  EXPECT_LE (poses, 22);
  // Every pose stands on the floor (y = 0): the body's lowest point within 4 cm of it.
  for (int f = 0; f < poses; ++f)
    EXPECT_NEAR (generator.body (0, f, 0).lowest, 0.0, 0.04) << f;
  const agex::SynthFrame frame = generator.render (0);
  EXPECT_EQ (frame.labels.size (), 5u);

  agex::SynthOptions bad = options;
  bad.thin_poses = 2.0;
  EXPECT_THROW (agex::SynthGenerator {bad}, std::invalid_argument);
  bad = options;
  bad.procedural_poses = -1;
  EXPECT_THROW (agex::SynthGenerator {bad}, std::invalid_argument);
}
}  // namespace

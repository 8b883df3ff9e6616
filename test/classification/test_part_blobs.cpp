// agex::PartBlobEstimation on hand-built label clouds: a hand at the end of an arm is found at
// its extremity even when single-tree hand votes are scattered over the torso (what PCL's
// forests do on real frames, and what made the mean-shift modes rank the torso over the hand).

#include <agex/classification/part_blobs.h>
#include <agex/classification/part_modes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{
constexpr float kF = 525.f, kZ = 2.f;

struct Scene
{
  pcl::PointCloud<agex::BodyPartLabelPoint> labels;
  pcl::Indices body;
  Eigen::Vector3f finger_tip;
};

void
put (Scene &s, int u, int v, float z, int label, float p_hand)
{
  agex::BodyPartLabelPoint &q = s.labels.at (u, v);
  q.x = (u - 160) * z / kF;
  q.y = (v - 120) * z / kF;
  q.z = z;
  q.label = label;
  q.p_hand = p_hand;
  q.p_head = q.p_foot = 0.f;
  q.p_other = 1.f - p_hand;
  s.body.push_back (v * 320 + u);
}

/** A 320x240 frame at 2 m: a torso (60x100 px) whose every other pixel has one tree of three
  * voting hand (label other body), an arm going right from it, and a hand (labelled by all
  * trees) at the arm's end, its finger tips at column 229. */
Scene
armWithHand ()
{
  Scene s;
  s.labels.width = 320;
  s.labels.height = 240;
  agex::BodyPartLabelPoint none;
  none.x = none.y = none.z = std::numeric_limits<float>::quiet_NaN ();
  none.label = agex::kLabelNone;
  s.labels.points.assign (320 * 240, none);
  for (int v = 70; v < 170; ++v)
    for (int u = 100; u < 160; ++u)
      put (s, u, v, kZ, agex::kLabelOtherBody, (u + v) % 2 ? 1.f / 3.f : 0.f);
  for (int v = 90; v < 98; ++v)
    for (int u = 160; u < 210; ++u)
      put (s, u, v, kZ, agex::kLabelOtherBody, 0.f);
  for (int v = 86; v < 102; ++v)
    for (int u = 210; u < 230; ++u)
      put (s, u, v, kZ, agex::kLabelHand, 1.f);
  s.finger_tip = s.labels.at (229, 94).getVector3fMap ();
  return s;
}
}  // namespace

TEST (PartBlobEstimation, HandAtTheArmsEndIsTheTopHandAtItsExtremity)
{
  const Scene s = armWithHand ();
  agex::PartBlobParams params;
  params.fx = params.fy = kF;
  agex::PartBlobEstimation blobs;
  blobs.setParams (params);
  std::vector<agex::PartMode> found;
  ASSERT_TRUE (blobs.compute (s.labels, s.body, found));
  ASSERT_FALSE (found.empty ());
  // The smoothing outvotes the scattered votes: the hand is the one hand blob.
  int hands = 0;
  for (const auto &m : found)
    hands += m.part == agex::kLabelHand;
  EXPECT_EQ (hands, 1);
  const agex::PartMode &top = found.front ();
  EXPECT_EQ (top.part, agex::kLabelHand);
  // At the finger tips: among the hand's last 3 cm (8 pixels at 2 m) away from the torso,
  // within 4 cm of the finger tips' middle.
  EXPECT_GE (top.tip_index % 320, 229 - 8);
  EXPECT_LT ((top.tip - s.finger_tip).norm (), 0.04f);
  // The hand's 16 x 20 pixels; the smoothing may give it an arm pixel or two beside it.
  EXPECT_GE (top.support.size (), 16u * 20u);
  EXPECT_LE (top.support.size (), 16u * 20u + 8u);
  // Mass: the hand's pixels of p = 1 at 2 m (an arm pixel taken in has p_hand 0).
  EXPECT_NEAR (top.mass, 320.f * kZ * kZ / (kF * kF), 1e-5f);
  EXPECT_GT (top.direction.x (), 0.7f);  // away from the body, towards a corner of the finger tips
}

TEST (PartBlobEstimation, MeanShiftModesRankTheScatteredVotesFirst)
{
  // What forest mode did before the blobs, on the same labels: the torso's single votes
  // make hand modes at least as confident as the hand (the reason for the blobs; if this
  // ever fails, the mean-shift modes have learnt to ignore scattered votes).
  const Scene s = armWithHand ();
  agex::PartModeParams params;
  params.fx = params.fy = kF;
  agex::PartModeEstimation modes;
  modes.setParams (params);
  std::vector<agex::PartMode> found;
  ASSERT_TRUE (modes.compute (s.labels, s.body, found));
  int false_hands = 0;
  for (const auto &m : found)
    false_hands += m.part == agex::kLabelHand && (m.tip - s.finger_tip).norm () > 0.1f;
  EXPECT_GT (false_hands, 0);
}

TEST (PartBlobEstimation, SpeckleBelowTheMinimumAreaIsNoBlob)
{
  Scene s = armWithHand ();
  agex::PartBlobParams params;
  params.fx = params.fy = kF;
  params.smoothing_radius = 0.f;  // the speckles stay
  agex::PartBlobEstimation blobs;
  blobs.setParams (params);
  std::vector<agex::PartMode> found;
  ASSERT_TRUE (blobs.compute (s.labels, s.body, found));
  // A lone hand pixel in the torso covers (2 / 525)^2 m^2, far below min_area.
  s.labels.at (130, 120).label = agex::kLabelHand;
  ASSERT_TRUE (blobs.compute (s.labels, s.body, found));
  int hands = 0;
  for (const auto &m : found)
    hands += m.part == agex::kLabelHand;
  EXPECT_EQ (hands, 1);
}

TEST (PartBlobEstimation, SettingsOutOfRangeAreRefusedByName)
{
  agex::PartBlobEstimation blobs;
  agex::PartBlobParams params;
  params.connect_distance = 0.f;
  try
  {
    blobs.setParams (params);
    FAIL () << "connect_distance 0 accepted";
  }
  catch (const std::invalid_argument &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("connect_distance"), std::string::npos) << e.what ();
  }
  params = agex::PartBlobParams ();
  params.smoothing_radius = std::numeric_limits<float>::quiet_NaN ();
  EXPECT_THROW (blobs.setParams (params), std::invalid_argument);
  params = agex::PartBlobParams ();
  params.min_area = -1.f;
  EXPECT_THROW (blobs.setParams (params), std::invalid_argument);
}

TEST (PartBlobEstimation, UnorganizedOrEmptyInputGivesNoBlobs)
{
  pcl::PointCloud<agex::BodyPartLabelPoint> labels;
  std::vector<agex::PartMode> found (3);
  agex::PartBlobEstimation blobs;
  EXPECT_FALSE (blobs.compute (labels, {}, found));
  EXPECT_TRUE (found.empty ());
  Scene s = armWithHand ();
  EXPECT_TRUE (blobs.compute (s.labels, {}, found));
  EXPECT_TRUE (found.empty ());
  s.body.push_back (-5);
  s.body.push_back (1 << 30);
  EXPECT_TRUE (blobs.compute (s.labels, s.body, found));
  EXPECT_FALSE (found.empty ());
}

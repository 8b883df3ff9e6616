// The fused detector: candidates from AGEX points and forest part modes (merging on
// hand-built inputs), a hand resting on the torso (no geodesic extremum) found by the fused
// detector where no AGEX point lies, the model and its forest saved and loaded with identical
// scores, and a model trained at one resolution scoring at another.

#include "test_support.h"

#include <agex/detection/body_part_detector.h>
#include <agex/detection/fused_candidates.h>
#include <agex/detection/tip_refinement.h>
#include <agex/detection/training_samples.h>

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace
{
using namespace agex_test;

// A forest of one test: a pixel nearer than 1.99 m is a hand, any other body pixel is other
// body. f(x) = d(x) - d(x + v s) with v far off the frame (clamped to the border, background
// 65535 mm): f > threshold exactly when d > 1990 mm.
agex::BodyPartForest::ConstPtr
handByDepthForest ()
{
  agex::BodyPartForest::Tree tree;
  tree.depth = 1;
  tree.complete = true;
  agex::BodyPartForest::Node node;
  node.du2 = 0;
  node.dv2 = 30000;
  node.threshold = 1990.f - 65535.f;
  tree.nodes = {node};
  tree.leaf_labels = {0, 1};
  std::vector<agex::BodyPartForest::ClassInfo> classes{{"hand", agex::kLabelHand}, {"other", agex::kLabelOtherBody}};
  return std::make_shared<agex::BodyPartForest> (classes, std::vector<agex::BodyPartForest::Tree>{tree}, 525.f,
                                                 agex::BodyPartForest::VoteRule::Average, -1);
}

/** A standing stick person at 2 m (head up, two legs, one arm held out) with a hand resting
  * flat on the torso 2 cm in front of it, at (hand_x, hand_y) metres. */
struct Scene
{
  Cloud::Ptr cloud;
  std::vector<agex::PartLabel> labels;
  Eigen::Vector3f hand = Eigen::Vector3f::Zero ();
};

Scene
makeScene (const Camera &cam, double hand_x, double hand_y, double shift)
{
  Figure body;
  body.centre = Eigen::Vector2d (shift, 0.0);
  body.depth = 2.0;
  body.disc_radius = 0.2;
  const double limb_angles[] = {-90.0, 70.0, 110.0, 10.0};  // head, legs, the arm held out
  const double lengths[] = {0.45, 0.85, 0.85, 0.55};
  for (int i = 0; i < 4; ++i)
  {
    const double a = limb_angles[i] * M_PI / 180.0;
    body.limbs.push_back ({Eigen::Vector2d (std::cos (a), std::sin (a)), lengths[i], i == 0 ? 0.1 : 0.06});
  }
  Figure hand;
  hand.centre = Eigen::Vector2d (shift + hand_x, hand_y);
  hand.depth = 1.98;
  hand.disc_radius = 0.05;
  Scene s;
  s.cloud = rasterise ({body, hand}, cam);
  auto label = [&] (agex::BodyPart part, int instance, const Eigen::Vector3f &tip, const Eigen::Vector3f &base) {
    agex::PartLabel l;
    l.part = part;
    l.instance = instance;
    l.tip = tip;
    l.base = base;
    l.visible = true;
    s.labels.push_back (l);
  };
  label (agex::BodyPart::Head, 0, body.tip3D (0), body.centre3D ());
  label (agex::BodyPart::Foot, 0, body.tip3D (1), body.centre3D ());
  label (agex::BodyPart::Foot, 1, body.tip3D (2), body.centre3D ());
  label (agex::BodyPart::Hand, 0, body.tip3D (3), body.centre3D ());
  s.hand = hand.centre3D ();
  label (agex::BodyPart::Hand, 1, s.hand, s.hand + Eigen::Vector3f (0.f, -0.1f, 0.02f));
  return s;
}

agex::DetectorSettings
fusedSettings ()
{
  agex::DetectorSettings settings;
  settings.kind = agex::DetectorKind::Fused;
  settings.pipeline.isolate_people = false;  // a stick figure without a floor: the box isolates it
  settings.pipeline.crop_min = Eigen::Vector3f (-2.f, -2.f, 1.f);
  settings.pipeline.crop_max = Eigen::Vector3f (2.f, 2.f, 3.f);
  settings.pipeline.median_window = 0;
  settings.pipeline.k = 6;
  settings.forest_file = "forest.agexforest";
  return settings;
}

/** A fused model trained on scenes with the resting hand at random places on the torso. */
agex::DetectorModel::ConstPtr
trainFused (const Camera &cam, const agex::BodyPartForest::ConstPtr &forest)
{
  const agex::DetectorSettings settings = fusedSettings ();
  const agex::PatchGeometry geometry{21, 0.6f, 0.3f};
  std::mt19937 rng (7);
  std::uniform_real_distribution<double> along (-0.08, 0.08);
  std::vector<agex::DepthPatch> patches;
  std::vector<std::vector<float>> auxiliary;
  std::vector<int> classes;
  for (int i = 0; i < 16; ++i)
  {
    const Scene scene = makeScene (cam, along (rng), 0.05 + along (rng), along (rng));
    const agex::DepthPipelineResult prepared = agex::runDepthPipeline (scene.cloud, settings.pipeline);
    pcl::PointCloud<agex::BodyPartLabelPoint> labels;
    std::vector<agex::PartMode> modes;
    agex::labelPersonParts (prepared, forest, static_cast<float> (cam.fx), static_cast<float> (cam.fy), 1, labels,
                            modes);
    agex::collectFusedTrainingSamples (prepared, labels, modes, static_cast<float> (cam.fx), settings.pipeline.up,
                                       settings.fused, scene.labels, 0.1f, geometry, patches, auxiliary, classes);
  }
  auto classifier = std::make_shared<agex::PatchClassifier> ();
  agex::PatchClassifierParams params;
  params.weak_count = 30;
  params.dictionary.fragments_per_class = 10;
  classifier->train (patches, auxiliary, agex::fusedFeatureNames (), classes, agex::kBodyPartCount, params);
  classifier->setPatchGeometry (geometry);
  return std::make_shared<const agex::DetectorModel> (classifier, settings);
}

/** The most confident hand detection's distance to p (infinity without a hand). */
float
handDistance (const std::vector<agex::BodyPartDetection> &detections, const Eigen::Vector3f &p, float *confidence)
{
  for (const auto &d : detections)
    if (d.part == agex::BodyPart::Hand && (d.position - p).norm () <= 0.1f)
    {
      *confidence = d.confidence;
      return (d.position - p).norm ();
    }
  *confidence = 0.f;
  return std::numeric_limits<float>::infinity ();
}

TEST (FusedCandidates, MergedWithinTheRadiusKeepingBothSources)
{
  agex::DepthPipelineResult prepared;
  prepared.filtered = nanCloud (20, 10);
  for (int u = 0; u < 20; ++u)
    (*prepared.filtered) (u, 5) = pcl::PointXYZ (0.01f * u, 0.f, 2.f);
  agex::InterestPoint p;
  p.getVector3fMap () = Eigen::Vector3f (0.f, 0.f, 2.f);
  p.u = 0, p.v = 5, p.rank = 2;
  p.getOrientationVector3fMap () = Eigen::Vector3f (-1.f, 0.f, 0.f);
  prepared.interest_points.push_back (p);
  agex::PartMode m;
  m.part = agex::kLabelHand;
  m.confidence = 0.8f;
  m.position = Eigen::Vector3f (0.10f, 0.f, 2.f);
  m.direction = Eigen::Vector3f (-1.f, 0.f, 0.f);
  m.tip = Eigen::Vector3f (0.01f, 0.f, 2.f);
  m.tip_index = 5 * 20 + 1;
  for (int u = 1; u <= 15; ++u)
    m.support.push_back (5 * 20 + u);
  agex::FusedCandidateParams params;
  params.merge_radius = 0.03f;
  const auto candidates = agex::fusedCandidates (prepared, {m}, params);
  // The AGEX point (x 0), the mode's tip 1 cm from it (merged into it), its peak (x 0.10) and
  // its other end (x 0.15): three candidates.
  ASSERT_EQ (candidates.size (), 3u);
  EXPECT_EQ (candidates[0].sources, agex::kFromAgex | agex::kFromModeTip);
  EXPECT_EQ (candidates[0].mode_part, agex::kLabelHand);
  EXPECT_FLOAT_EQ (candidates[0].position.x (), 0.f);  // the AGEX point is kept
  EXPECT_EQ (candidates[1].sources, agex::kFromModePosition);
  EXPECT_NEAR (candidates[1].position.x (), 0.10f, 1e-6f);
  EXPECT_EQ (candidates[2].sources, agex::kFromModeEnd);
  EXPECT_NEAR (candidates[2].position.x (), 0.15f, 1e-6f);
  EXPECT_NEAR (candidates[2].orientation.x (), 1.f, 1e-6f);  // pointing the other way
  // Without merging every source stands alone; low-confidence modes give none.
  params.merge_radius = 0.f;
  EXPECT_EQ (agex::fusedCandidates (prepared, {m}, params).size (), 4u);
  params.min_mode_confidence = 0.9f;
  EXPECT_EQ (agex::fusedCandidates (prepared, {m}, params).size (), 1u);
}

TEST (FusedDetector, AHandRestingOnTheTorsoIsFoundWhereNoAgexPointIs)
{
  const Camera cam{262.5, 262.5, 159.5, 119.5, 320, 240};
  const auto forest = handByDepthForest ();
  const auto model = trainFused (cam, forest);
  const Scene scene = makeScene (cam, 0.03, 0.02, 0.02);

  agex::BodyPartDetector<pcl::PointXYZ> detector;
  detector.setModel (model);
  detector.setForest (forest);
  detector.setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
  detector.setInputCloud (scene.cloud);
  std::vector<agex::BodyPartDetection> detections;
  detector.compute (detections);

  // Not a geodesic extremum: no AGEX point near it, so the AGEX-only detector cannot name it.
  for (const auto &p : detector.getIntermediate ().interest_points)
    EXPECT_GT ((p.getVector3fMap () - scene.hand).norm (), 0.1f) << "rank " << p.rank;
  float confidence = 0.f;
  EXPECT_LE (handDistance (detections, scene.hand, &confidence), 0.1f);
  EXPECT_GT (confidence, 0.5f);
  // The held-out arm's hand and the head are still found through their AGEX points.
  bool head = false;
  for (const auto &d : detections)
    head = head || (d.part == agex::BodyPart::Head && d.confidence > 0.5f &&
                    (d.position - scene.labels[0].tip).norm () <= 0.1f);
  EXPECT_TRUE (head);
}

TEST (FusedDetector, ModelAndForestSavedAndLoadedScoreTheSame)
{
  const Camera cam{262.5, 262.5, 159.5, 119.5, 320, 240};
  const auto forest = handByDepthForest ();
  const auto model = trainFused (cam, forest);
  TempDir dir;
  forest->save (dir.file ("forest.agexforest"));
  agex::DetectorSettings settings = model->settings ();
  settings.forest_bytes = fs::file_size (dir.file ("forest.agexforest"));
  agex::DetectorModel (model->classifierPtr (), settings).save (dir.file ("fused.yml"));

  const Scene scene = makeScene (cam, -0.04, 0.06, -0.03);
  agex::BodyPartDetector<pcl::PointXYZ> original;
  original.setModel (model);
  original.setForest (forest);
  original.setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
  original.setInputCloud (scene.cloud);
  std::vector<agex::BodyPartDetection> a, b;
  original.compute (a);

  const auto loaded = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (dir.file ("fused.yml"));
  ASSERT_TRUE (loaded->getForest ()) << "fromModel did not load the model's forest";
  loaded->setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
  loaded->setInputCloud (scene.cloud);
  loaded->compute (b);
  ASSERT_FALSE (a.empty ());
  ASSERT_EQ (a.size (), b.size ());
  for (std::size_t i = 0; i < a.size (); ++i)
  {
    EXPECT_EQ (a[i].part, b[i].part);
    EXPECT_EQ (bits (a[i].confidence), bits (b[i].confidence)) << i;
    EXPECT_EQ (a[i].u, b[i].u);
    EXPECT_EQ (a[i].v, b[i].v);
  }
}

TEST (FusedDetector, AModelTrainedAtOneResolutionScoresAtAnother)
{
  // The same field of view at 320x240 (training) and 640x480 (test): metric patches and
  // depth-scaled forest offsets make the resting hand look the same.
  const Camera low{262.5, 262.5, 159.5, 119.5, 320, 240};
  const Camera high{525.0, 525.0, 319.5, 239.5, 640, 480};
  const auto forest = handByDepthForest ();
  const auto model = trainFused (low, forest);
  for (const Camera &cam : {low, high})
  {
    SCOPED_TRACE (std::to_string (cam.width) + "x" + std::to_string (cam.height));
    const Scene scene = makeScene (cam, 0.05, 0.08, 0.0);
    agex::BodyPartDetector<pcl::PointXYZ> detector;
    detector.setModel (model);
    detector.setForest (forest);
    detector.setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
    detector.setInputCloud (scene.cloud);
    std::vector<agex::BodyPartDetection> detections;
    detector.compute (detections);
    float confidence = 0.f;
    EXPECT_LE (handDistance (detections, scene.hand, &confidence), 0.1f);
    EXPECT_GT (confidence, 0.5f);
  }
}

/** A sliding-window model trained on the same scenes as trainFused (upright patches). */
agex::DetectorModel::ConstPtr
trainWindows (const Camera &cam)
{
  agex::DetectorSettings settings = fusedSettings ();
  settings.kind = agex::DetectorKind::SlidingWindow;
  settings.forest_file.clear ();
  const agex::PatchGeometry geometry{21, 0.5f, 0.3f};
  std::mt19937 rng (9);
  std::mt19937_64 sample_rng (9);
  std::uniform_real_distribution<double> along (-0.08, 0.08);
  std::vector<agex::DepthPatch> patches;
  std::vector<int> classes;
  for (int i = 0; i < 12; ++i)
  {
    const Scene scene = makeScene (cam, along (rng), 0.05 + along (rng), along (rng));
    const agex::DepthPipelineResult prepared = agex::runDepthPipeline (scene.cloud, settings.pipeline);
    agex::collectWindowTrainingSamples (prepared, scene.labels, 0.1f, 2, 0.03f, 20, geometry, sample_rng, patches,
                                        classes);
  }
  auto classifier = std::make_shared<agex::PatchClassifier> ();
  agex::PatchClassifierParams params;
  params.weak_count = 30;
  params.dictionary.fragments_per_class = 10;
  classifier->train (patches, classes, agex::kBodyPartCount, params);
  classifier->setPatchGeometry (geometry);
  return std::make_shared<const agex::DetectorModel> (classifier, settings);
}
}  // namespace

// The sliding window's confidences blend into each fused candidate's: weight 0 changes
// nothing, weight 1 leaves each detection exactly the window classifier's confidence for its
// class on the upright patch at its pixel, and only sliding-window models and weights in
// [0, 1] are accepted.
TEST (FusedDetector, WindowRescoringBlendsTheSlidingWindowsConfidenceAtEachCandidate)
{
  const Camera cam{262.5, 262.5, 159.5, 119.5, 320, 240};
  const auto forest = handByDepthForest ();
  const auto model = trainFused (cam, forest);
  const auto windows = trainWindows (cam);
  const Scene scene = makeScene (cam, 0.03, 0.04, 0.01);
  const auto run = [&] (const agex::DetectorModel::ConstPtr &window_model, float weight,
                        agex::DepthPipelineResult *intermediate) {
    agex::BodyPartDetector<pcl::PointXYZ> detector;
    detector.setModel (model);
    detector.setForest (forest);
    detector.setWindowRescoring (window_model, weight);
    detector.setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
    detector.setInputCloud (scene.cloud);
    std::vector<agex::BodyPartDetection> detections;
    detector.compute (detections);
    if (intermediate)
      *intermediate = detector.getIntermediate ();
    return detections;
  };
  const auto plain = run (nullptr, 0.f, nullptr);
  const auto zero = run (windows, 0.f, nullptr);
  ASSERT_FALSE (plain.empty ());
  ASSERT_EQ (zero.size (), plain.size ());
  for (std::size_t i = 0; i < plain.size (); ++i)
  {
    EXPECT_EQ (zero[i].part, plain[i].part);
    EXPECT_EQ (bits (zero[i].confidence), bits (plain[i].confidence)) << i;
  }

  agex::DepthPipelineResult prepared;
  const auto window_only = run (windows, 1.f, &prepared);
  ASSERT_FALSE (window_only.empty ());
  ASSERT_TRUE (prepared.filtered);
  const int width = static_cast<int> (prepared.filtered->width);
  bool changed = false;
  for (const auto &d : window_only)
  {
    pcl::PointCloud<agex::InterestPoint> at;
    agex::InterestPoint p;
    p.getVector3fMap () = (*prepared.filtered)[d.v * width + d.u].getVector3fMap ();
    p.orientation[0] = p.orientation[1] = p.orientation[2] = 0.f;
    p.u = d.u;
    p.v = d.v;
    at.push_back (p);
    std::vector<agex::DepthPatch> patch;
    agex::computePatches (prepared, at, windows->patchGeometry (), patch);
    ASSERT_EQ (patch.size (), 1u);
    std::vector<float> margins (agex::kBodyPartCount), confidences (agex::kBodyPartCount);
    windows->classifier ().classify (patch[0], margins.data (), confidences.data ());
    EXPECT_FLOAT_EQ (d.confidence, confidences[static_cast<std::size_t> (d.part)]) << d.u << "," << d.v;
    EXPECT_EQ (static_cast<int> (std::max_element (confidences.begin (), confidences.end ()) - confidences.begin ()),
               static_cast<int> (d.part));
    for (const auto &q : plain)
      changed = changed || (q.u == d.u && q.v == d.v && bits (q.confidence) != bits (d.confidence));
  }
  EXPECT_TRUE (changed) << "the window classifier gave every candidate the fused classifier's confidence";

  agex::BodyPartDetector<pcl::PointXYZ> detector;
  EXPECT_THROW (detector.setWindowRescoring (windows, 1.5f), std::invalid_argument);
  EXPECT_THROW (detector.setWindowRescoring (windows, -0.1f), std::invalid_argument);
  EXPECT_THROW (detector.setWindowRescoring (windows, std::numeric_limits<float>::quiet_NaN ()),
                std::invalid_argument);
  EXPECT_THROW (detector.setWindowRescoring (model, 0.5f), std::invalid_argument);
  detector.setWindowRescoring (windows, 0.5f);
  EXPECT_EQ (detector.getWindowModel (), windows);
  EXPECT_FLOAT_EQ (detector.getWindowWeight (), 0.5f);
}

// A fused model names its sliding-window model relative to itself, with the weight: fromModel
// loads it and scores as setWindowRescoring does; a missing or wrong window model is an error
// naming it; models without the keys name none.
TEST (FusedDetector, AModelNamesItsWindowModelWhichFromModelLoads)
{
  const Camera cam{262.5, 262.5, 159.5, 119.5, 320, 240};
  const auto forest = handByDepthForest ();
  const auto model = trainFused (cam, forest);
  const auto windows = trainWindows (cam);
  TempDir dir;
  forest->save (dir.file ("forest.agexforest"));
  windows->save (dir.file ("windows.yml"));
  agex::DetectorSettings settings = model->settings ();
  settings.forest_bytes = fs::file_size (dir.file ("forest.agexforest"));
  agex::DetectorModel (model->classifierPtr (), settings).save (dir.file ("plain.yml"));
  settings.window_file = "windows.yml";
  settings.window_weight = 0.4f;
  agex::DetectorModel (model->classifierPtr (), settings).save (dir.file ("fused.yml"));

  EXPECT_TRUE (agex::DetectorModel::load (dir.file ("plain.yml")).windowPath ().empty ());
  const agex::DetectorModel loaded_model = agex::DetectorModel::load (dir.file ("fused.yml"));
  EXPECT_EQ (fs::path (loaded_model.windowPath ()), fs::path (dir.file ("windows.yml")));
  EXPECT_FLOAT_EQ (loaded_model.settings ().window_weight, 0.4f);
  const auto loaded = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (dir.file ("fused.yml"));
  ASSERT_TRUE (loaded->getWindowModel ()) << "fromModel did not load the model's window model";
  EXPECT_FLOAT_EQ (loaded->getWindowWeight (), 0.4f);
  EXPECT_FALSE (agex::BodyPartDetector<pcl::PointXYZ>::fromModel (dir.file ("plain.yml"))->getWindowModel ());

  const Scene scene = makeScene (cam, -0.02, 0.05, 0.02);
  agex::BodyPartDetector<pcl::PointXYZ> direct;
  direct.setModel (model);
  direct.setForest (forest);
  direct.setWindowRescoring (windows, 0.4f);
  std::vector<agex::BodyPartDetection> a, b;
  for (auto *detector : {&direct, loaded.get ()})
  {
    detector->setFocalLength (static_cast<float> (cam.fx), static_cast<float> (cam.fy));
    detector->setInputCloud (scene.cloud);
    detector->compute (detector == &direct ? a : b);
  }
  ASSERT_FALSE (a.empty ());
  ASSERT_EQ (a.size (), b.size ());
  for (std::size_t i = 0; i < a.size (); ++i)
  {
    EXPECT_EQ (a[i].part, b[i].part);
    EXPECT_EQ (bits (a[i].confidence), bits (b[i].confidence)) << i;
  }

  // The window model must be there, and be a sliding-window model.
  fs::rename (dir.file ("windows.yml"), dir.file ("moved.yml"));
  try
  {
    agex::BodyPartDetector<pcl::PointXYZ>::fromModel (dir.file ("fused.yml"));
    ADD_FAILURE () << "a missing window model was not an error";
  }
  catch (const agex::ModelError &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("windows.yml"), std::string::npos) << e.what ();
  }
  fs::copy_file (dir.file ("plain.yml"), dir.file ("windows.yml"));
  EXPECT_THROW (agex::BodyPartDetector<pcl::PointXYZ>::fromModel (dir.file ("fused.yml")), agex::ModelError);
  settings.window_weight = 1.5f;
  EXPECT_THROW (agex::DetectorModel (model->classifierPtr (), settings), std::invalid_argument);
}

TEST (TrainingExamples, BackgroundThinnedToTheRatioKeepingEveryPositiveInOrder)
{
  // 6 positives and 40 background examples, each patch marked by its index.
  std::vector<agex::DepthPatch> patches (46);
  std::vector<std::vector<float>> auxiliary (46);
  std::vector<int> classes (46, -1);
  for (int i = 0; i < 46; ++i)
  {
    patches[i].patch[0] = static_cast<float> (i);
    auxiliary[i] = {static_cast<float> (i)};
    if (i % 7 == 0 && i < 42)
      classes[i] = i % 3;
  }
  std::mt19937_64 rng (3);
  auto p = patches;
  auto a = auxiliary;
  auto c = classes;
  EXPECT_EQ (agex::keepBackgroundAtMost (2.f, rng, p, a, c), 28u);
  ASSERT_EQ (p.size (), 18u);
  ASSERT_EQ (a.size (), 18u);
  ASSERT_EQ (c.size (), 18u);
  int positives = 0;
  for (std::size_t i = 0; i < p.size (); ++i)
  {
    const int original = static_cast<int> (p[i].patch[0]);
    EXPECT_EQ (a[i][0], p[i].patch[0]) << "a patch and its features stay together";
    EXPECT_EQ (c[i], classes[original]);
    if (i > 0)
    {
      EXPECT_GT (original, static_cast<int> (p[i - 1].patch[0])) << "the order is kept";
    }
    positives += c[i] >= 0;
  }
  EXPECT_EQ (positives, 6);

  // Another seed keeps another choice of background.
  std::mt19937_64 other_rng (4);
  auto p2 = patches;
  auto a2 = auxiliary;
  auto c2 = classes;
  agex::keepBackgroundAtMost (2.f, other_rng, p2, a2, c2);
  bool differs = false;
  for (std::size_t i = 0; i < p.size (); ++i)
    differs = differs || p[i].patch[0] != p2[i].patch[0];
  EXPECT_TRUE (differs);

  // Ratio 0, or one above what there is, keeps everything; no auxiliary features is fine.
  std::vector<std::vector<float>> none;
  p = patches;
  c = classes;
  EXPECT_EQ (agex::keepBackgroundAtMost (0.f, rng, p, none, c), 0u);
  EXPECT_EQ (agex::keepBackgroundAtMost (7.f, rng, p, none, c), 0u);
  EXPECT_EQ (p.size (), 46u);
  EXPECT_EQ (agex::keepBackgroundAtMost (0.5f, rng, p, none, c), 37u);
  EXPECT_EQ (p.size (), 9u);

  // Mismatched counts and a bad ratio are refused, nothing changed.
  c.pop_back ();
  EXPECT_THROW (agex::keepBackgroundAtMost (1.f, rng, p, none, c), std::invalid_argument);
  c = classes;
  p = patches;
  EXPECT_THROW (agex::keepBackgroundAtMost (std::nanf (""), rng, p, none, c), std::invalid_argument);
  EXPECT_THROW (agex::keepBackgroundAtMost (-1.f, rng, p, none, c), std::invalid_argument);
  EXPECT_EQ (p.size (), 46u);
}

namespace
{
agex::ScoredCandidate
scoredAt (agex::BodyPart part, float confidence, const Eigen::Vector3f &position, int rank, float geodesic, int mesh = 0)
{
  agex::ScoredCandidate s;
  s.detection.part = part;
  s.detection.confidence = confidence;
  s.detection.position = position;
  s.detection.orientation = Eigen::Vector3f::UnitY ();
  s.detection.u = static_cast<int> (100 * position.x ()) + 50;
  s.detection.v = static_cast<int> (100 * position.y ()) + 50;
  s.detection.rank = rank;
  s.detection.mesh = mesh;
  s.confidences[static_cast<std::size_t> (part)] = confidence;
  s.geodesic_distance = geodesic;
  return s;
}
}  // namespace

// One person's mesh 0, AGEX points as AGEX ranks them (rank 1 the centroid, then each extremum
// found at a geodesic distance no larger than the one before): a hand held beside the head
// (rank 2), the head (3), the toe (4), the heel (5). A foot found at the ankle (a part mode) and
// one at the heel move to the toe; a hand found at the wrist moves to the hand's point; the head
// stays, though the hand beside it is a more salient extremum the classifier also takes for a
// head; nothing moves beyond the radius or to another mesh.
TEST (TipRefinement, HandsAndFeetMoveToTheirPartsMostSalientExtremumTheClassifierAgreesWith)
{
  using agex::BodyPart;
  const auto part = [] (BodyPart p) { return static_cast<std::size_t> (p); };
  std::vector<agex::ScoredCandidate> scored{
    scoredAt (BodyPart::Foot, 0.1f, {0.f, -0.3f, 2.f}, 1, 0.f),       // 0 the centroid
    scoredAt (BodyPart::Hand, 0.9f, {0.08f, -1.f, 2.f}, 2, 1.4f),     // 1 the hand beside the head
    scoredAt (BodyPart::Head, 0.9f, {0.f, -1.f, 2.f}, 3, 1.2f),       // 2 the head
    scoredAt (BodyPart::Foot, 0.6f, {0.f, 0.8f, 2.f}, 4, 1.1f),       // 3 the toe
    scoredAt (BodyPart::Foot, 0.7f, {0.f, 0.75f, 2.05f}, 5, 0.3f),    // 4 the heel
    scoredAt (BodyPart::Foot, 0.9f, {0.f, 0.72f, 2.f}, 0, 0.f),       // 5 the ankle, a part mode
    scoredAt (BodyPart::Hand, 0.95f, {0.08f, -0.92f, 2.f}, 0, 0.f),   // 6 the wrist, a part mode
    scoredAt (BodyPart::Foot, 0.8f, {0.03f, 0.72f, 2.f}, 2, 1.5f, 1), // 7 another person's foot
  };
  scored[2].confidences[part (BodyPart::Hand)] = 0.2f;
  scored[1].confidences[part (BodyPart::Head)] = 0.8f;  // the classifier half takes the hand for a head
  scored[1].confidences[part (BodyPart::Foot)] = 0.6f;  // and for a foot (too far from the feet)

  const auto off = agex::refineToTips (scored, agex::TipRefinementParams ());
  ASSERT_EQ (off.size (), scored.size ());
  for (std::size_t i = 0; i < off.size (); ++i)
    EXPECT_TRUE (off[i].position.isApprox (scored[i].detection.position)) << i;

  agex::TipRefinementParams params;
  params.radius = 0.1f;
  const auto moved = agex::refineToTips (scored, params);
  ASSERT_EQ (moved.size (), scored.size ());
  const auto at = [&] (std::size_t i, std::size_t where) {
    return moved[i].position.isApprox (scored[where].detection.position) && moved[i].u == scored[where].detection.u &&
           moved[i].v == scored[where].detection.v && moved[i].rank == scored[where].detection.rank;
  };
  EXPECT_TRUE (at (5, 3)) << "the ankle goes to the toe";
  EXPECT_TRUE (at (4, 3)) << "the heel goes to the toe";
  EXPECT_TRUE (at (6, 1)) << "the wrist goes to the hand";
  EXPECT_EQ (moved[5].part, BodyPart::Foot);
  EXPECT_FLOAT_EQ (moved[5].confidence, 0.9f);
  EXPECT_EQ (moved[6].part, BodyPart::Hand);
  EXPECT_FLOAT_EQ (moved[6].confidence, 0.95f);
  for (const std::size_t stays : {0u, 1u, 2u, 3u, 7u})
    EXPECT_TRUE (at (stays, stays)) << stays;

  // The classifier must agree: with the toe under half the ankle's confidence for a foot, the
  // ankle goes to the next extremum that reaches it, the heel; asking for 0.8, not even there.
  scored[3].confidences[part (BodyPart::Foot)] = 0.4f;
  const auto doubted = agex::refineToTips (scored, params);
  EXPECT_TRUE (doubted[5].position.isApprox (scored[4].detection.position));
  params.min_relative_confidence = 0.8f;  // 0.7 is under 0.8 of 0.9
  EXPECT_TRUE (agex::refineToTips (scored, params)[5].position.isApprox (scored[5].detection.position));

  params.radius = 0.6f;
  EXPECT_THROW (params.validate ([] (const std::string &k) { return k; }), std::invalid_argument);
  params.radius = 0.1f;
  params.min_relative_confidence = 0.f;
  EXPECT_THROW (params.validate ([] (const std::string &k) { return k; }), std::invalid_argument);
  params.min_relative_confidence = std::numeric_limits<float>::quiet_NaN ();
  EXPECT_THROW (params.validate ([] (const std::string &k) { return k; }), std::invalid_argument);
}

// The 2D contour-landmark module: imglab XML round trip and bad files, automatic
// annotation of hand-built masks (count, on the outline, start, direction, anchors,
// mirror symmetry), a small shape-predictor training run on synthetic figures, and the
// apps run as built (COCO annotation from ../shared, the bundled model on a bundled image).

#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/people_detector.h>
#include <agex/landmarks/person_masks.h>

#include "test_support.h"

#ifdef AGEX_LANDMARKS_APP_SUPPORT
#include <agex/apps/landmarks.h>
#endif

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <chrono>
#include <random>

#include <sys/wait.h>

namespace
{
using agex_test::readAll;
using agex_test::writeAll;
namespace fs = std::filesystem;

fs::path
tempDir (const std::string &name)
{
  const fs::path dir = fs::temp_directory_path () / ("agex_test_landmarks_" + name + "_" + std::to_string (::getpid ()));
  fs::remove_all (dir);
  fs::create_directories (dir);
  return dir;
}

// A figure with a round head, a trunk, arms out at arm_angle (radians below horizontal)
// and legs apart: its extremities are known.
struct Figure
{
  cv::Mat mask;
  cv::Point2f head_top, hand_left, hand_right, foot_left, foot_right;
};

Figure
drawFigure (cv::Size size, cv::Point2f centre, float scale, float arm_angle, float leg_spread)
{
  Figure f;
  f.mask = cv::Mat::zeros (size, CV_8UC1);
  const float head_r = 12 * scale;
  const cv::Point2f neck = centre + cv::Point2f (0, -40 * scale), hip = centre + cv::Point2f (0, 30 * scale);
  const cv::Point2f head = neck + cv::Point2f (0, -head_r);
  const float arm = 55 * scale, leg = 70 * scale, thick = 7 * scale;
  f.head_top = head + cv::Point2f (0, -head_r);
  const cv::Point2f shoulder = neck + cv::Point2f (0, 8 * scale);
  f.hand_left = shoulder + cv::Point2f (-std::cos (arm_angle), std::sin (arm_angle)) * arm;
  f.hand_right = shoulder + cv::Point2f (std::cos (arm_angle), std::sin (arm_angle)) * arm;
  f.foot_left = hip + cv::Point2f (-std::sin (leg_spread), std::cos (leg_spread)) * leg;
  f.foot_right = hip + cv::Point2f (std::sin (leg_spread), std::cos (leg_spread)) * leg;
  cv::circle (f.mask, head, static_cast<int> (head_r), 255, cv::FILLED);
  cv::line (f.mask, neck, hip, 255, static_cast<int> (4 * thick));
  for (const cv::Point2f &end : {f.hand_left, f.hand_right})
    cv::line (f.mask, shoulder, end, 255, static_cast<int> (thick));
  for (const cv::Point2f &end : {f.foot_left, f.foot_right})
    cv::line (f.mask, hip, end, 255, static_cast<int> (1.5f * thick));
  // The drawn ends stick out by half the line width.
  auto tip = [&] (const cv::Point2f &from, const cv::Point2f &to, float half) {
    const cv::Point2f d = to - from;
    return to + d * (half / static_cast<float> (cv::norm (d)));
  };
  f.hand_left = tip (shoulder, f.hand_left, thick / 2);
  f.hand_right = tip (shoulder, f.hand_right, thick / 2);
  f.foot_left = tip (hip, f.foot_left, 0.75f * thick);
  f.foot_right = tip (hip, f.foot_right, 0.75f * thick);
  return f;
}

double
distanceToMaskEdge (const cv::Mat &mask, const cv::Point2f &p)
{
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours (mask.clone (), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  double best = 1e9;
  for (const auto &c : contours)
    for (const auto &q : c)
      best = std::min (best, cv::norm (cv::Point2f (q) - p));
  return best;
}

TEST (ImglabDataset, RoundTripKeepsEverything)
{
  agex::ImglabDataset dataset;
  dataset.name = "people & <friends>";
  dataset.comment = "it's \"quoted\"";
  agex::ImglabImage image;
  image.file = "images/a b.png";
  agex::ImglabBox box;
  box.rect = cv::Rect (10, 20, 30, 40);
  box.label = "person";
  box.parts["000"] = cv::Point2f (11, 21);
  box.parts["left_shoulder"] = cv::Point2f (-3, 400);
  image.boxes.push_back (box);
  image.boxes.push_back ({cv::Rect (1, 2, 3, 4), "", true, {}});
  dataset.images.push_back (image);
  dataset.images.push_back ({"empty.jpg", {}});

  const fs::path dir = tempDir ("roundtrip");
  const std::string path = (dir / "set.xml").string ();
  agex::writeImglabDataset (path, dataset);
  const agex::ImglabDataset back = agex::readImglabDataset (path);
  EXPECT_EQ (back.name, dataset.name);
  EXPECT_EQ (back.comment, dataset.comment);
  ASSERT_EQ (back.images.size (), 2u);
  EXPECT_EQ (back.images[0].file, "images/a b.png");
  ASSERT_EQ (back.images[0].boxes.size (), 2u);
  EXPECT_EQ (back.images[0].boxes[0].rect, box.rect);
  EXPECT_EQ (back.images[0].boxes[0].label, "person");
  EXPECT_FALSE (back.images[0].boxes[0].ignore);
  EXPECT_TRUE (back.images[0].boxes[1].ignore);
  EXPECT_EQ (back.images[0].boxes[0].parts.size (), 2u);
  EXPECT_EQ (back.images[0].boxes[0].parts.at ("left_shoulder"), cv::Point2f (-3, 400));
  EXPECT_TRUE (back.images[1].boxes.empty ());
  EXPECT_EQ (agex::imglabDatasetXml (back), readAll (path));
  EXPECT_EQ (agex::resolveImglabImagePath (path, "x.png"), (dir / "x.png").string ());
  fs::remove_all (dir);
}

TEST (ImglabDataset, ReadsImglabStyleFiles)
{
  // As imglab writes them: double quotes elsewhere, comments, the stylesheet line.
  const fs::path dir = tempDir ("style");
  const std::string path = (dir / "faces.xml").string ();
  writeAll (path, "<?xml version=\"1.0\"?>\n<?xml-stylesheet type='text/xsl' href='x.xsl'?>\n<!-- a comment -->\n"
                  "<dataset><name>f</name><images>\n<image file=\"2008_002470.jpg\">\n"
                  "  <box top=\"181\" left=\"274\" width=\"52\" height=\"53\"><part name=\"01\" x=\"280\" y=\"200\"/></box>\n"
                  "  <box top='1' left='2' width='3' height='4'/>\n</image></images></dataset>\n");
  const agex::ImglabDataset d = agex::readImglabDataset (path);
  ASSERT_EQ (d.images.size (), 1u);
  ASSERT_EQ (d.images[0].boxes.size (), 2u);
  EXPECT_EQ (d.images[0].boxes[0].rect, cv::Rect (274, 181, 52, 53));
  EXPECT_EQ (d.images[0].boxes[0].parts.at ("01"), cv::Point2f (280, 200));
  fs::remove_all (dir);
}

TEST (ImglabDataset, BadFilesNameTheFileAndTheProblem)
{
  const fs::path dir = tempDir ("bad");
  const std::string path = (dir / "bad.xml").string ();
  auto expect_error = [&] (const std::string &content, const std::string &problem) {
    writeAll (path, content);
    try
    {
      agex::readImglabDataset (path);
      ADD_FAILURE () << "no error for: " << content;
    }
    catch (const std::runtime_error &e)
    {
      EXPECT_NE (std::string (e.what ()).find (path), std::string::npos) << e.what ();
      EXPECT_NE (std::string (e.what ()).find (problem), std::string::npos) << e.what ();
    }
  };
  expect_error ("", "no XML element");
  expect_error ("<html></html>", "not <dataset>");
  expect_error ("<dataset><images><image file='a'><box top='1' left='2' width='3'/></image></images></dataset>",
                "no 'height' attribute");
  expect_error ("<dataset><images><image file='a'><box top='x' left='2' width='3' height='4'/></image></images></dataset>",
                "not a number");
  expect_error ("<dataset><images><image file='a'>", "never closed");
  expect_error ("<dataset><images></image></dataset>", "closes <images>");
  expect_error ("<dataset>\n\n<images><image/></images></dataset>", "line 3");
  // A person box of no area would wreck a shape predictor's training; an ignore box may be one.
  expect_error ("<dataset><images><image file='a'><box top='1' left='2' width='0' height='0'/></image></images></dataset>",
                "zero width or height");
  writeAll (path, "<dataset><images><image file='a'><box top='1' left='2' width='0' height='0' ignore='1'/>"
                  "</image></images></dataset>");
  EXPECT_NO_THROW (agex::readImglabDataset (path));
  EXPECT_THROW (agex::readImglabDataset ((dir / "missing.xml").string ()), std::runtime_error);
  fs::remove_all (dir);
}

// A 350 KB file nested 50,000 deep overflowed the stack of the recursive parser (issue #18):
// now a clear error naming the file and the line, at any depth beyond the bound.
TEST (ImglabDataset, DeepNestingIsAClearErrorNotAStackOverflow)
{
  const fs::path dir = tempDir ("deep");
  const std::string path = (dir / "deep.xml").string ();
  std::string deep = "<dataset>\n<images>\n<image file='a.png'>\n";
  for (int i = 0; i < 50000; ++i)
    deep += "<a>";
  for (int i = 0; i < 50000; ++i)
    deep += "</a>";
  deep += "\n</image></images></dataset>\n";
  writeAll (path, deep);
  try
  {
    agex::readImglabDataset (path);
    ADD_FAILURE () << "a 50,000-deep file was read";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find (path + ": line 4: elements nested more than 64 deep"), std::string::npos)
      << e.what ();
  }
  // Unknown elements nested to the bound are still skipped.
  std::string nested = "<dataset><images><image file='a.png'>";
  for (int i = 0; i < 61; ++i)
    nested += "<a>";
  for (int i = 0; i < 61; ++i)
    nested += "</a>";
  writeAll (path, nested + "<box top='1' left='2' width='3' height='4'/></image></images></dataset>");
  const agex::ImglabDataset d = agex::readImglabDataset (path);
  ASSERT_EQ (d.images.size (), 1u);
  EXPECT_EQ (d.images[0].boxes.size (), 1u);
  fs::remove_all (dir);
}

// A large flat file is read in linear time (the line numbers were counted from the start for
// every element): 900 images of 180 parts, as agex_annotate writes for CCP.
TEST (ImglabDataset, LargeFilesAreReadQuickly)
{
  agex::ImglabDataset dataset;
  for (int i = 0; i < 900; ++i)
  {
    agex::ImglabImage image;
    image.file = std::to_string (i) + ".jpg";
    agex::ImglabBox box;
    box.rect = cv::Rect (1, 2, 300, 300);
    for (int k = 0; k < 180; ++k)
      box.parts[agex::contourLandmarkName (k)] = cv::Point2f (10.f + k, 20.f);
    image.boxes.push_back (box);
    dataset.images.push_back (image);
  }
  const fs::path dir = tempDir ("large");
  const std::string path = (dir / "large.xml").string ();
  agex::writeImglabDataset (path, dataset);
  const auto start = std::chrono::steady_clock::now ();
  const agex::ImglabDataset back = agex::readImglabDataset (path);
  const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
  EXPECT_EQ (back.images.size (), 900u);
  // Six header lines, then 184 per image (image, box, 180 parts, end of box, end of image).
  EXPECT_EQ (back.images[899].boxes[0].line, 8 + 184 * 899);
  // Quadratic counting took minutes; linear reading takes well under a second even on a busy
  // machine (a bound that only catches the quadratic behaviour, not a timing target).
  EXPECT_LT (seconds, 20.0);
  fs::remove_all (dir);
}

TEST (ContourAnnotation, LandmarkNamesAndMirror)
{
  EXPECT_EQ (agex::contourLandmarkName (7), "007");
  EXPECT_EQ (agex::contourLandmarkIndex ("179"), 179);
  EXPECT_EQ (agex::contourLandmarkIndex ("180"), -1);
  EXPECT_EQ (agex::contourLandmarkIndex ("left_shoulder"), -1);
  EXPECT_EQ (agex::mirroredContourLandmark (0), 0);
  EXPECT_EQ (agex::mirroredContourLandmark (36), 144);
  EXPECT_EQ (agex::mirroredContourLandmark (72), 108);
  for (int i = 0; i < agex::kContourLandmarkCount; ++i)
    EXPECT_EQ (agex::mirroredContourLandmark (agex::mirroredContourLandmark (i)), i);
}

// Without hints: the anchors come from the outline's shape alone.
TEST (ContourAnnotation, FigureWithoutHintsStartsAtTheHeadAndGoesCounterClockwise)
{
  const Figure f = drawFigure (cv::Size (320, 320), cv::Point2f (160, 160), 1.5f, 0.5f, 0.35f);
  agex::ContourAnnotationParams exact;
  exact.closing_px = 0;  // closing would round off the armpits and the crotch
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors (), exact);
  ASSERT_TRUE (a.ok) << a.problem;
  ASSERT_EQ (a.landmarks.size (), 180u);
  for (const cv::Point2f &p : a.landmarks)
    EXPECT_LT (distanceToMaskEdge (f.mask, p), 1.5) << p;
  EXPECT_LT (cv::norm (a.landmarks[0] - f.head_top), 3.0);
  // Counter-clockwise on screen from the head top: first to the left, down the left side.
  EXPECT_LT (a.landmarks[3].x, a.landmarks[0].x - 3);
  EXPECT_GT (a.landmarks[177].x, a.landmarks[0].x + 3);
  EXPECT_LT (cv::norm (a.landmarks[36] - f.hand_left), 8.0) << a.landmarks[36];
  EXPECT_LT (cv::norm (a.landmarks[72] - f.foot_left), 8.0) << a.landmarks[72];
  EXPECT_LT (cv::norm (a.landmarks[108] - f.foot_right), 8.0) << a.landmarks[108];
  EXPECT_LT (cv::norm (a.landmarks[144] - f.hand_right), 8.0) << a.landmarks[144];
  EXPECT_FALSE (a.anchors_reordered);
  EXPECT_EQ (a.box.width, a.box.height);
  EXPECT_TRUE (a.box.contains (cv::Point (a.tight_box.x, a.tight_box.y)));
  // Even spacing by arc length within a segment.
  const double first = cv::norm (a.landmarks[1] - a.landmarks[0]);
  EXPECT_NEAR (cv::norm (a.landmarks[2] - a.landmarks[1]), first, 2.0);
}

// Hints put the anchors where they say, even where the shape alone would choose otherwise.
TEST (ContourAnnotation, HintsMoveTheAnchors)
{
  // Arms hanging down: the shape alone finds no clear hand.
  const Figure f = drawFigure (cv::Size (320, 320), cv::Point2f (160, 150), 1.5f, 1.2f, 0.35f);
  agex::ContourAnchors hints;
  hints.head = f.head_top + cv::Point2f (0, 15);
  hints.hands = {f.hand_right, f.hand_left};  // any order
  hints.feet = {f.foot_left, f.foot_right};
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, hints);
  ASSERT_TRUE (a.ok) << a.problem;
  EXPECT_LT (cv::norm (a.landmarks[0] - f.head_top), 3.0);
  EXPECT_LT (cv::norm (a.landmarks[36] - f.hand_left), 3.0) << a.landmarks[36];
  EXPECT_LT (cv::norm (a.landmarks[144] - f.hand_right), 3.0) << a.landmarks[144];
  EXPECT_LT (cv::norm (a.landmarks[72] - f.foot_left), 3.0);
  EXPECT_LT (cv::norm (a.landmarks[108] - f.foot_right), 3.0);
  for (int k = 0; k < agex::kContourAnchorCount; ++k)
    EXPECT_TRUE (a.anchor_from_hint[k]) << k;

  // Unlabelled extremities (as AGEX gives them) are labelled by position.
  agex::ContourAnchors extremities;
  extremities.extremities = {f.foot_right, f.hand_left, f.head_top, f.foot_left, f.hand_right};
  const agex::ContourAnnotation b = agex::annotateContour (f.mask, extremities);
  ASSERT_TRUE (b.ok) << b.problem;
  for (int i = 0; i < agex::kContourLandmarkCount; ++i)
    EXPECT_LT (cv::norm (a.landmarks[i] - b.landmarks[i]), 3.0) << i;
}

TEST (ContourAnnotation, MirroredMaskGivesMirroredLandmarks)
{
  const Figure f = drawFigure (cv::Size (321, 320), cv::Point2f (150, 160), 1.5f, 0.3f, 0.25f);
  cv::Mat mirrored;
  cv::flip (f.mask, mirrored, 1);
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
  const agex::ContourAnnotation b = agex::annotateContour (mirrored, agex::ContourAnchors ());
  ASSERT_TRUE (a.ok && b.ok);
  for (int i = 0; i < agex::kContourLandmarkCount; i += 9)
  {
    const cv::Point2f p = b.landmarks[agex::mirroredContourLandmark (i)];
    EXPECT_LT (cv::norm (a.landmarks[i] - cv::Point2f (320 - p.x, p.y)), 4.0) << i;
  }
}

TEST (ContourAnnotation, CocoKeypointsAndPolygons)
{
  std::vector<cv::Point3f> k (17, cv::Point3f (0, 0, 0));
  k[0] = {100, 50, 2};   // nose
  k[5] = {90, 80, 2};    // shoulders
  k[6] = {110, 80, 2};
  k[7] = {80, 110, 2};   // left elbow, wrist
  k[9] = {80, 140, 2};
  k[11] = {95, 150, 2};  // hips
  k[12] = {105, 150, 2};
  const agex::ContourAnchors a = agex::anchorsFromCocoKeypoints (k);
  EXPECT_EQ (a.head, cv::Point2f (100, 50));
  ASSERT_EQ (a.hands.size (), 1u);
  EXPECT_EQ (a.hands[0], cv::Point2f (80, 152));  // 0.4 of the forearm beyond the wrist
  EXPECT_TRUE (a.feet.empty ());
  EXPECT_NEAR (a.up.y, -1.f, 1e-5f);
  EXPECT_TRUE (agex::anchorsFromCocoKeypoints ({}).hands.empty ());

  const cv::Mat mask = agex::maskFromPolygons (cv::Size (50, 40), {{10, 10, 30, 10, 30, 20, 10, 20}, {1, 1}});
  EXPECT_EQ (mask.at<unsigned char> (15, 20), 255);
  EXPECT_EQ (mask.at<unsigned char> (5, 5), 0);
  EXPECT_EQ (cv::countNonZero (mask), 21 * 11);
}

TEST (ContourAnnotation, BadMasksAreRejectedNotCrashed)
{
  EXPECT_FALSE (agex::annotateContour (cv::Mat (), agex::ContourAnchors ()).ok);
  EXPECT_FALSE (agex::annotateContour (cv::Mat::zeros (50, 50, CV_8UC1), agex::ContourAnchors ()).ok);
  EXPECT_FALSE (agex::annotateContour (cv::Mat::zeros (50, 50, CV_32FC1), agex::ContourAnchors ()).ok);
  cv::Mat speck = cv::Mat::zeros (50, 50, CV_8UC1);
  speck.at<unsigned char> (10, 10) = 255;
  const agex::ContourAnnotation a = agex::annotateContour (speck, agex::ContourAnchors ());
  EXPECT_FALSE (a.ok);
  EXPECT_FALSE (a.problem.empty ());
  agex::ContourAnchors nan_hints;
  nan_hints.hands = {cv::Point2f (NAN, 1)};
  nan_hints.up = cv::Point2f (0, 0);
  EXPECT_TRUE (agex::annotateContour (drawFigure (cv::Size (200, 200), cv::Point2f (100, 100), 1.f, 0.4f, 0.3f).mask,
                                      nan_hints).ok);
}

TEST (ContourAnnotation, DistanceToPolyline)
{
  const std::vector<cv::Point2f> square{{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  EXPECT_NEAR (agex::meanDistanceToClosedPolyline ({{5, 2}, {5, 5}, {12, 5}}, square), (2 + 5 + 2) / 3.0, 1e-9);
}

// Without hints, hands that hang down have no extremity on the outline: the hand anchors are
// put at the wrist's height on the outer side of each arm, the same place on every upright
// person (and not on an elbow, a hip or a coat's widest point, wherever that happens to be).
TEST (ContourAnnotation, HangingArmsAnchorAtTheWristHeight)
{
  const Figure f = drawFigure (cv::Size (320, 320), cv::Point2f (160, 150), 1.5f, 1.2f, 0.35f);
  agex::ContourAnnotationParams exact;
  exact.closing_px = 0;
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors (), exact);
  ASSERT_TRUE (a.ok) << a.problem;
  const float top = a.tight_box.y, height = static_cast<float> (a.tight_box.height - 1);
  const float wrist = top + exact.wrist_drop * height;
  for (const int anchor : {36, 144})
  {
    EXPECT_NEAR (a.landmarks[anchor].y, wrist, 2.0) << anchor;
    // On the arm, outside the trunk (21 pixels either side of the middle).
    EXPECT_GT (std::abs (a.landmarks[anchor].x - 160.f), 24.f) << a.landmarks[anchor];
  }
  EXPECT_LT (a.landmarks[36].x, 160.f);
  EXPECT_GT (a.landmarks[144].x, 160.f);
  // Arms held out are anchored at their tips.
  const Figure out = drawFigure (cv::Size (320, 320), cv::Point2f (160, 160), 1.5f, 0.5f, 0.35f);
  const agex::ContourAnnotation b = agex::annotateContour (out.mask, agex::ContourAnchors (), exact);
  ASSERT_TRUE (b.ok);
  EXPECT_LT (cv::norm (b.landmarks[36] - out.hand_left), 8.0);
  EXPECT_LT (cv::norm (b.landmarks[144] - out.hand_right), 8.0);
}

// A hand raised above the head is the highest point, but off to the side: the head top stays
// landmark 0.
TEST (ContourAnnotation, RaisedHandIsNotTheHeadTop)
{
  Figure f = drawFigure (cv::Size (320, 320), cv::Point2f (160, 170), 1.5f, 1.2f, 0.35f);
  // From the side of the trunk (the stick figure's arms start at its middle), up past the head.
  const cv::Point2f shoulder (160 - 20, 170 - 60 + 12), hand = shoulder + cv::Point2f (-51, -64);
  cv::line (f.mask, shoulder, hand, 255, 10);
  ASSERT_LT (hand.y, f.head_top.y);
  const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
  ASSERT_TRUE (a.ok) << a.problem;
  EXPECT_LT (cv::norm (a.landmarks[0] - f.head_top), 4.0) << a.landmarks[0];
}

// Synthetic figures on textured backgrounds: a small cascade must beat the mean shape
// placed in the box by a wide margin on figures it has not seen.
TEST (ContourShapePredictor, TrainingOnSyntheticFiguresReducesTheError)
{
  std::mt19937 rng (5);
  std::uniform_real_distribution<float> arm (-0.6f, 1.3f), legs (0.1f, 0.5f), shift (-10.f, 10.f), scale (0.9f, 1.1f);
  auto make = [&] (int count) {
    std::vector<agex::LandmarkTrainingImage> set;
    for (int i = 0; i < count; ++i)
    {
      const Figure f = drawFigure (cv::Size (200, 200), cv::Point2f (100 + shift (rng), 95 + shift (rng)), scale (rng),
                                   arm (rng), legs (rng));
      const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
      if (!a.ok)
        continue;
      agex::LandmarkTrainingImage t;
      cv::Mat noise (f.mask.size (), CV_8UC1);
      cv::randu (noise, 0, 80);
      t.grey = noise + f.mask / 2;
      t.boxes.push_back (a.box);
      t.shapes.push_back (a.landmarks);
      set.push_back (t);
    }
    return set;
  };
  const auto train = make (40), test = make (10);
  ASSERT_GE (test.size (), 8u);
  agex::ShapePredictorTrainingParams params;
  params.oversampling_amount = 10;
  params.cascade_depth = 6;
  params.num_trees_per_cascade_level = 60;
  params.num_threads = 2;
  const agex::ContourShapePredictor predictor = agex::ContourShapePredictor::train (train, params);
  EXPECT_EQ (predictor.landmarkCount (), 180);

  // The mean shape, in box coordinates.
  std::vector<cv::Point2f> mean_shape (180, cv::Point2f (0, 0));
  for (const auto &t : train)
    for (int i = 0; i < 180; ++i)
      mean_shape[i] += cv::Point2f ((t.shapes[0][i].x - t.boxes[0].x) / t.boxes[0].width,
                                    (t.shapes[0][i].y - t.boxes[0].y) / t.boxes[0].height) *
                       (1.f / train.size ());
  double trained_error = 0, mean_error = 0;
  for (const auto &t : test)
  {
    const auto predicted = predictor.predict (t.grey, t.boxes[0]);
    ASSERT_EQ (predicted.size (), 180u);
    for (int i = 0; i < 180; ++i)
    {
      trained_error += cv::norm (predicted[i] - t.shapes[0][i]);
      const cv::Point2f placed (t.boxes[0].x + mean_shape[i].x * t.boxes[0].width,
                                t.boxes[0].y + mean_shape[i].y * t.boxes[0].height);
      mean_error += cv::norm (placed - t.shapes[0][i]);
    }
  }
  EXPECT_LT (trained_error, 0.6 * mean_error) << trained_error / (180 * test.size ()) << " px vs "
                                               << mean_error / (180 * test.size ()) << " px";

  // Save, load, same predictions; bad files are named.
  const fs::path dir = tempDir ("predictor");
  const std::string path = (dir / "model.dat").string ();
  predictor.save (path);
  const agex::ContourShapePredictor loaded = agex::ContourShapePredictor::load (path);
  EXPECT_EQ (loaded.predict (test[0].grey, test[0].boxes[0]), predictor.predict (test[0].grey, test[0].boxes[0]));
  writeAll ((dir / "junk.dat").string (), "not a model");
  try
  {
    agex::ContourShapePredictor::load ((dir / "junk.dat").string ());
    ADD_FAILURE () << "junk loaded";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("junk.dat"), std::string::npos);
  }
  EXPECT_THROW (agex::ContourShapePredictor::train ({}, params), std::invalid_argument);
  EXPECT_THROW (agex::PeopleDetector::load ((dir / "junk.dat").string ()), std::runtime_error);
  fs::remove_all (dir);
}

TEST (PeopleDetector, BoxIoU)
{
  EXPECT_DOUBLE_EQ (agex::boxIoU (cv::Rect (0, 0, 10, 10), cv::Rect (0, 0, 10, 10)), 1.0);
  EXPECT_FLOAT_EQ (static_cast<float> (agex::boxIoU (cv::Rect (0, 0, 10, 10), cv::Rect (5, 0, 10, 10))), 50.f / 150.f);
  EXPECT_DOUBLE_EQ (agex::boxIoU (cv::Rect (0, 0, 10, 10), cv::Rect (20, 0, 10, 10)), 0.0);
  EXPECT_TRUE (agex::PeopleDetector::openCvDefault ().detect (cv::Mat ()).empty ());
}

// The OpenCV fallback on a half-size image: the people it finds at full size (tall enough
// for the halved image) are found again, with boxes in the full image's pixels.
TEST (PeopleDetector, OpenCvFallbackOnResizedImage)
{
  const cv::Mat image = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (image.empty ());
  const auto full = agex::PeopleDetector::openCvDefault (1.0).detect (image);
  const auto half = agex::PeopleDetector::openCvDefault (0.5).detect (image);
  ASSERT_FALSE (full.empty ());
  ASSERT_FALSE (half.empty ());
  const cv::Rect frame (0, 0, image.cols, image.rows);
  for (const auto &person : half)
    EXPECT_GT ((person.box & frame).area (), 0.8 * person.box.area ()) << person.box;
  int matched = 0;
  for (const auto &a : full)
  {
    if (a.box.height < 200)  // about 96 / 0.5 pixels: too small for the half-size image
      continue;
    for (const auto &b : half)
      if (agex::boxIoU (a.box, b.box) > 0.5)
      {
        ++matched;
        break;
      }
  }
  EXPECT_GE (matched, 1);
  // A tiny image is no error, just no people.
  EXPECT_TRUE (agex::PeopleDetector::openCvDefault (0.1).detect (cv::Mat (100, 60, CV_8UC3, cv::Scalar::all (80))).empty ());
  EXPECT_THROW (agex::PeopleDetector::openCvDefault (0.0), std::invalid_argument);
  EXPECT_THROW (agex::PeopleDetector::openCvDefault (5.0), std::invalid_argument);
}

// Bright figures on noise: the fhog detector trained on a few finds a new one, and a saved
// detector gives the same boxes.
TEST (PeopleDetector, TrainsOnSyntheticFiguresAndRoundTrips)
{
  std::mt19937 rng (3);
  std::uniform_real_distribution<float> arm (-0.5f, 1.2f), legs (0.15f, 0.45f), where (70.f, 170.f);
  auto make = [&] (cv::Rect *box) {
    const Figure f = drawFigure (cv::Size (240, 240), cv::Point2f (where (rng), 115), 0.9f, arm (rng), legs (rng));
    *box = agex::annotateContour (f.mask, agex::ContourAnchors ()).box;
    cv::Mat noise (f.mask.size (), CV_8UC1);
    cv::randu (noise, 0, 60);
    return cv::Mat (noise + f.mask * 0.7);
  };
  std::vector<cv::Mat> images;
  std::vector<std::vector<cv::Rect>> boxes;
  for (int i = 0; i < 8; ++i)
  {
    cv::Rect box;
    images.push_back (make (&box));
    boxes.push_back ({box});
  }
  agex::PeopleDetectorTrainingParams params;
  params.window_width = params.window_height = 64;
  params.num_threads = 2;
  const agex::PeopleDetector detector = agex::PeopleDetector::train (images, boxes, params);
  EXPECT_FALSE (detector.isOpenCvDefault ());
  cv::Rect truth;
  const cv::Mat test = make (&truth);
  const auto found = detector.detect (test);
  ASSERT_FALSE (found.empty ());
  double best = 0;
  for (const auto &d : found)
    best = std::max (best, agex::boxIoU (d.box, truth));
  EXPECT_GT (best, 0.5);

  const fs::path dir = tempDir ("detector");
  const std::string path = (dir / "people.svm").string ();
  detector.save (path);
  const auto again = agex::PeopleDetector::load (path).detect (test);
  ASSERT_EQ (again.size (), found.size ());
  for (std::size_t i = 0; i < found.size (); ++i)
    EXPECT_EQ (again[i].box, found[i].box);
  EXPECT_THROW (agex::PeopleDetector::openCvDefault ().save (path), std::logic_error);
  EXPECT_THROW (agex::PeopleDetector::train ({}, {}, params), std::invalid_argument);
  fs::remove_all (dir);
}

// Trained on one figure per image, the detector still keeps two people whose boxes overlap
// apart: dlib would take the suppression from the training boxes ("any overlap" when no two
// overlap), and of two people side by side find one.
TEST (PeopleDetector, NeighboursWithOverlappingBoxesAreBothFound)
{
  std::mt19937 rng (3);
  std::uniform_real_distribution<float> arm (-0.5f, 1.2f), legs (0.15f, 0.45f), where (70.f, 170.f);
  std::vector<cv::Mat> images;
  std::vector<std::vector<cv::Rect>> boxes;
  for (int i = 0; i < 8; ++i)
  {
    const Figure f = drawFigure (cv::Size (240, 240), cv::Point2f (where (rng), 115), 0.9f, arm (rng), legs (rng));
    cv::Mat noise (f.mask.size (), CV_8UC1);
    cv::randu (noise, 0, 60);
    images.push_back (noise + f.mask * 0.7);
    boxes.push_back ({agex::annotateContour (f.mask, agex::ContourAnchors ()).box});
  }
  agex::PeopleDetectorTrainingParams params;
  params.window_width = params.window_height = 64;
  params.num_threads = 2;
  const agex::PeopleDetector detector = agex::PeopleDetector::train (images, boxes, params);
  const Figure a = drawFigure (cv::Size (320, 240), cv::Point2f (120, 115), 0.9f, 1.0f, 0.3f);
  const Figure b = drawFigure (cv::Size (320, 240), cv::Point2f (200, 115), 0.9f, 1.0f, 0.3f);
  const cv::Rect box_a = agex::annotateContour (a.mask, agex::ContourAnchors ()).box;
  const cv::Rect box_b = agex::annotateContour (b.mask, agex::ContourAnchors ()).box;
  ASSERT_GT (agex::boxIoU (box_a, box_b), 0.1);  // the boxes overlap
  cv::Mat noise (a.mask.size (), CV_8UC1);
  cv::randu (noise, 0, 60);
  const auto found = detector.detect (cv::Mat (noise + (a.mask | b.mask) * 0.7));
  for (const cv::Rect &truth : {box_a, box_b})
  {
    double best = 0;
    for (const auto &d : found)
      best = std::max (best, agex::boxIoU (d.box, truth));
    EXPECT_GT (best, 0.5) << truth;
  }
}

// Every training image has two figures, one boxed and one in an ignore region. Had the
// unboxed figure counted as background, the positives and negatives would look alike; as an
// ignore region it does not, and the detector finds both figures of a new image (trained
// without the regions, it found neither).
TEST (PeopleDetector, IgnoreRegionsAreNotBackground)
{
  std::mt19937 rng (5);
  std::uniform_real_distribution<float> arm (-0.5f, 1.2f), legs (0.15f, 0.45f), jitter (-8.f, 8.f);
  auto make = [&] (cv::Rect *left, cv::Rect *right) {
    const Figure a = drawFigure (cv::Size (400, 240), cv::Point2f (100 + jitter (rng), 115), 0.9f, arm (rng), legs (rng));
    const Figure b = drawFigure (cv::Size (400, 240), cv::Point2f (300 + jitter (rng), 115), 0.9f, arm (rng), legs (rng));
    *left = agex::annotateContour (a.mask, agex::ContourAnchors ()).box;
    *right = agex::annotateContour (b.mask, agex::ContourAnchors ()).box;
    cv::Mat noise (a.mask.size (), CV_8UC1);
    cv::randu (noise, 0, 60);
    return cv::Mat (noise + (a.mask | b.mask) * 0.7);
  };
  std::vector<cv::Mat> images;
  std::vector<std::vector<cv::Rect>> boxes, regions;
  for (int i = 0; i < 8; ++i)
  {
    cv::Rect left, right;
    images.push_back (make (&left, &right));
    boxes.push_back ({i % 2 ? left : right});
    regions.push_back ({i % 2 ? right : left});
  }
  agex::PeopleDetectorTrainingParams params;
  params.window_width = params.window_height = 64;
  params.num_threads = 2;
  EXPECT_THROW (agex::PeopleDetector::train (images, boxes, {}, params), std::invalid_argument);
  const agex::PeopleDetector detector = agex::PeopleDetector::train (images, boxes, regions, params);
  cv::Rect left, right;
  const cv::Mat test = make (&left, &right);
  const auto found = detector.detect (test);
  for (const cv::Rect &truth : {left, right})
  {
    double best = 0;
    for (const auto &d : found)
      best = std::max (best, agex::boxIoU (d.box, truth));
    EXPECT_GT (best, 0.5) << truth;
  }
}

// Scaling a tiny image down must not reach OpenCV with an empty size: the image simply holds
// no box the window can match.
TEST (PeopleDetector, TrainingOnTinyImagesAtASmallScaleIsAClearError)
{
  agex::PeopleDetectorTrainingParams params;
  params.scale = 0.1;
  params.num_threads = 1;
  try
  {
    agex::PeopleDetector::train ({cv::Mat (3, 2, CV_8UC1, cv::Scalar (9))}, {{cv::Rect (0, 0, 2, 3)}}, params);
    ADD_FAILURE () << "trained on a box no window can match";
  }
  catch (const std::invalid_argument &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("no box"), std::string::npos) << e.what ();
  }
}

#ifdef AGEX_LANDMARKS_APP_SUPPORT
// A box with some but not all 180 landmarks names its line; boxes without any are kept out of
// training with a warning, not silently.
TEST (LandmarkApps, PartlyAnnotatedBoxesAreNamedByLine)
{
  const fs::path dir = tempDir ("partial_boxes");
  ASSERT_TRUE (cv::imwrite ((dir / "a.png").string (), cv::Mat (40, 30, CV_8UC1, cv::Scalar (50))));
  auto dataset = [&] (int parts) {
    agex::ImglabDataset d;
    agex::ImglabImage image;
    image.file = "a.png";
    agex::ImglabBox box;
    box.rect = cv::Rect (2, 3, 20, 30);
    for (int i = 0; i < parts; ++i)
      box.parts[agex::contourLandmarkName (i)] = cv::Point2f (5.f + i % 10, 6.f + i / 10);
    image.boxes = {box, box};
    image.boxes[0].parts.clear ();
    d.images.push_back (image);
    const std::string path = (dir / ("d" + std::to_string (parts) + ".xml")).string ();
    agex::writeImglabDataset (path, d);
    return path;
  };
  const std::string partial = dataset (179);
  try
  {
    agex::apps::loadLandmarkDataset (partial);
    ADD_FAILURE () << "a box with 179 landmarks was accepted";
  }
  catch (const std::runtime_error &e)
  {
    // The second <box> of the file.
    const std::string xml = readAll (partial);
    const std::size_t second_box = xml.find ("<box", xml.find ("<box") + 1);
    const long line = 1 + std::count (xml.begin (), xml.begin () + static_cast<long> (second_box), '\n');
    EXPECT_NE (std::string (e.what ()).find (partial + ": line " + std::to_string (line) + ": a box in a.png has 179 of the 180"),
               std::string::npos)
      << e.what ();
  }
  testing::internal::CaptureStderr ();
  const auto images = agex::apps::loadLandmarkDataset (dataset (180));
  const std::string warning = testing::internal::GetCapturedStderr ();
  ASSERT_EQ (images.size (), 1u);
  EXPECT_EQ (images[0].people.size (), 1u);
  EXPECT_EQ (images[0].ignored.size (), 1u);
  EXPECT_NE (warning.find ("1 box(es) without contour landmarks"), std::string::npos) << warning;
  fs::remove_all (dir);
}
#endif

#ifdef AGEX_LANDMARKS_APP_SUPPORT
// All-point interpolated AP by hand: hits at ranks 1 and 3 of 3 truths: precision 1 up to
// recall 1/3, then 2/3 up to recall 2/3 (the 0.5 at rank 2 is lifted to rank 3's 2/3).
TEST (LandmarkEvaluation, AveragePrecisionByHand)
{
  EXPECT_NEAR (agex::apps::averagePrecision ({{0.9, true}, {0.8, false}, {0.7, true}}, 3), 1.0 / 3 + 2.0 / 9, 1e-12);
  EXPECT_NEAR (agex::apps::averagePrecision ({{0.7, true}, {0.9, true}}, 2), 1.0, 1e-12);  // sorted by score
  EXPECT_DOUBLE_EQ (agex::apps::averagePrecision ({{0.9, false}}, 1), 0.0);
  EXPECT_DOUBLE_EQ (agex::apps::averagePrecision ({}, 0), 0.0);
}
#endif

#ifdef AGEX_ANNOTATE_EXECUTABLE
int
run (const std::string &command)
{
  return std::system ((command + " > /dev/null 2>&1").c_str ());
}

TEST (LandmarkApps, AnnotateCocoPeople)
{
  const std::string json = agex_test::sharedData ("people2d/coco/test_coco.json");
  AGEX_REQUIRE_SHARED_FILE (json, "the COCO people of ../shared/data/people2d");
  const fs::path dir = tempDir ("coco");
  const std::string xml = (dir / "coco.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + json + " --images " +
                  agex_test::sharedData ("people2d/coco") + " --out " + xml),
             0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 4u);
  int people = 0, ignored = 0;
  for (const auto &image : d.images)
  {
    EXPECT_TRUE (fs::exists (agex::resolveImglabImagePath (xml, image.file))) << image.file;
    for (const auto &box : image.boxes)
    {
      if (box.ignore)
      {
        ++ignored;
        continue;
      }
      ++people;
      int landmarks = 0;
      for (const auto &[name, p] : box.parts)
        if (agex::contourLandmarkIndex (name) >= 0)
        {
          ++landmarks;
          EXPECT_TRUE (cv::Rect (box.rect.x - 1, box.rect.y - 1, box.rect.width + 2, box.rect.height + 2).contains (p));
        }
      EXPECT_EQ (landmarks, 180);
    }
  }
  EXPECT_GE (people, 10);
  EXPECT_EQ (people + ignored, 14);
  // Bad input: a missing JSON is named.
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + (dir / "none.json").string () +
                  " --images " + dir.string () + " --out " + xml),
             0);
  fs::remove_all (dir);
}

TEST (LandmarkApps, AnnotateRgbdFrame)
{
  const std::string pcd = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the RGB-D frame of ../shared/data/kinect");
  const fs::path dir = tempDir ("rgbd");
  const std::string xml = (dir / "rgbd.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + pcd + " --out " + xml), 0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  const cv::Mat colour = cv::imread (agex::resolveImglabImagePath (xml, d.images[0].file));
  EXPECT_EQ (colour.size (), cv::Size (640, 480));
  int people = 0;
  for (const auto &box : d.images[0].boxes)
    if (!box.ignore)
    {
      ++people;
      EXPECT_EQ (box.parts.size (), 180u);
      // A standing person: the head top is the highest landmark region, the feet low.
      EXPECT_LT (box.parts.at ("000").y, box.parts.at ("072").y);
      EXPECT_LT (box.parts.at ("000").y, box.parts.at ("108").y);
    }
  EXPECT_EQ (people, 5);  // the five people walking away
  fs::remove_all (dir);
}

TEST (LandmarkApps, BundledModelOnBundledImage)
{
  const std::string image = std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg";
  const fs::path dir = tempDir ("app");
  const std::string json = (dir / "out.json").string (), overlay = (dir / "out.png").string ();
  ASSERT_EQ (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + image + " --json " + json + " --overlay " + overlay), 0);
  const nlohmann::json doc = nlohmann::json::parse (readAll (json));
  ASSERT_EQ (doc["frames"].size (), 1u);
  for (const auto &person : doc["frames"][0]["people"])
    EXPECT_EQ (person["landmarks"].size (), 180u);
  EXPECT_FALSE (cv::imread (overlay).empty ());
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + (dir / "missing.png").string ()), 0);
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " " + image + " --model " + image), 0);
  fs::remove_all (dir);
}
TEST (LandmarkApps, BadImagesAndModelsAreNamedAndOutputsNeverLandOnInputs)
{
  const fs::path dir = tempDir ("bad_apps");
  const std::string app = AGEX_LANDMARKS_EXECUTABLE;
  auto exit_code = [] (const std::string &command) {
    const int status = std::system ((command + " > /dev/null 2>&1").c_str ());
    return WIFEXITED (status) ? WEXITSTATUS (status) : -1;  // -1: killed by a signal
  };
  const std::string good = std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg";
  const std::string jpeg = readAll (good), truncated = (dir / "truncated.jpg").string ();
  writeAll (truncated, jpeg.substr (0, jpeg.size () / 2));
  EXPECT_EQ (exit_code (app + " " + good), 0);
  // OpenCV would decode the first half with grey rows below it and a warning.
  EXPECT_EQ (exit_code (app + " " + truncated), 1);
  // Too small for the detector's window: no people, not an error.
  const std::string tiny = (dir / "tiny.png").string ();
  ASSERT_TRUE (cv::imwrite (tiny, cv::Mat (1, 1, CV_8UC3, cv::Scalar::all (90))));
  EXPECT_EQ (exit_code (app + " " + tiny + " --json " + (dir / "tiny.json").string ()), 0);
  // Damaged dlib models whose indices point outside the model, and one with 5 landmarks.
  for (const char *model : {"shape_predictor_bad_anchor.dat", "shape_predictor_bad_split.dat",
                            "shape_predictor_5_landmarks.dat"})
    EXPECT_EQ (exit_code (app + " " + good + " --model " + AGEX_SOURCE_DIR + "/test/bad_inputs/inputs/" + model), 1)
      << model;
  // An image-sequence video: the overlay may not replace one of its frames.
  std::vector<std::string> frames;
  for (int n = 0; n < 3; ++n)
  {
    frames.push_back ((dir / cv::format ("f%03d.png", n)).string ());
    ASSERT_TRUE (cv::imwrite (frames.back (), cv::Mat (64, 48, CV_8UC3, cv::Scalar::all (40 * n))));
  }
  const std::string before = readAll (frames[1]);
  EXPECT_EQ (exit_code (app + " --video " + (dir / "f%03d.png").string () + " --overlay " + frames[1]), 1);
  EXPECT_EQ (readAll (frames[1]), before);
  EXPECT_EQ (exit_code (app + " --video " + (dir / "f%03d.png").string () + " --overlay " +
                        (dir / "overlay.png").string ()),
             0);
  // A file that opens but yields no frame, and a camera number no camera has.
  writeAll ((dir / "notes.txt").string (), "not a video");
  EXPECT_EQ (exit_code (app + " --video " + (dir / "notes.txt").string ()), 1);
  EXPECT_EQ (exit_code (app + " --video 99999999999"), 1);
  fs::remove_all (dir);
}

TEST (LandmarkApps, AnnotationImagesAreStagedAndNeverOverwritten)
{
  const std::string pcd = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (pcd, "the RGB-D frame of ../shared/data/kinect");
  const fs::path dir = tempDir ("rgbd_names");
  // Two inputs of the same name (frames/000000.pcd of two agex_synth runs) get two images.
  for (const char *run_dir : {"a", "b"})
  {
    fs::create_directories (dir / run_dir);
    fs::copy_file (pcd, dir / run_dir / "frame.pcd");
  }
  const std::string a = (dir / "a" / "frame.pcd").string (), b = (dir / "b" / "frame.pcd").string ();
  const std::string xml = (dir / "out.xml").string ();
  ASSERT_EQ (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + a + " " + b + " --out " + xml), 0);
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 2u);
  EXPECT_NE (d.images[0].file, d.images[1].file);
  // A failing run (a damaged second input) leaves the earlier dataset's images as they were,
  // and no staging folder behind. (The marker stands for an earlier image: both inputs here
  // render the same picture.)
  const std::string image = agex::resolveImglabImagePath (xml, d.images[0].file), kept = "an earlier image";
  writeAll (image, kept);
  const std::string damaged = (dir / "damaged.pcd").string ();
  writeAll (damaged, readAll (pcd).substr (0, 3000));
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + b + " " + damaged + " --out " + xml), 0);
  EXPECT_EQ (readAll (image), kept);
  for (const auto &entry : fs::directory_iterator (fs::path (image).parent_path ()))
    EXPECT_EQ (entry.path ().filename ().string ().rfind (".agex_staging", 0), std::string::npos) << entry.path ();
  // Overlays may not land on the dataset's own images.
  EXPECT_NE (run (std::string (AGEX_ANNOTATE_EXECUTABLE) + " rgbd " + a + " --out " + xml + " --overlay-dir " +
                  fs::path (image).parent_path ().string ()),
             0);
  EXPECT_EQ (readAll (image), kept);
  fs::remove_all (dir);
}

TEST (LandmarkApps, VideoFileFrameByFrame)
{
  // A short MJPEG AVI written with OpenCV's own encoder (no FFmpeg needed): each of its
  // frames must give the people that the same decoded frame gives as a still image.
  const fs::path dir = tempDir ("video");
  const std::string video = (dir / "walk.avi").string ();
  const cv::Mat still = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (still.empty ());
  {
    cv::VideoWriter writer (video, cv::CAP_OPENCV_MJPEG, cv::VideoWriter::fourcc ('M', 'J', 'P', 'G'), 10.0,
                            still.size ());
    ASSERT_TRUE (writer.isOpened ());
    cv::Mat shifted;
    for (int n = 0; n < 3; ++n)
    {
      // The people move 20 pixels to the right per frame.
      const cv::Mat shift = (cv::Mat_<double> (2, 3) << 1, 0, 20 * n, 0, 1, 0);
      cv::warpAffine (still, shifted, shift, still.size ());
      writer.write (shifted);
    }
  }
  std::vector<std::string> decoded;
  {
    cv::VideoCapture capture (video);  // the backend the app opens it with
    cv::Mat frame;
    while (capture.read (frame) && !frame.empty ())
    {
      decoded.push_back ((dir / ("frame" + std::to_string (decoded.size ()) + ".png")).string ());
      ASSERT_TRUE (cv::imwrite (decoded.back (), frame));
    }
  }
  ASSERT_EQ (decoded.size (), 3u);

  // OpenCV's detector finds these pedestrians seen from behind (the bundled one, trained on
  // frontal street-fashion photos, does not); the video path is the same for either.
  const std::string app = std::string (AGEX_LANDMARKS_EXECUTABLE) + " --opencv-detector";
  const std::string from_video = (dir / "video.json").string (), from_stills = (dir / "stills.json").string ();
  ASSERT_EQ (run (app + " --video " + video + " --json " + from_video), 0);
  std::string stills_command = app;
  for (const auto &frame : decoded)
    stills_command += " " + frame;
  ASSERT_EQ (run (stills_command + " --json " + from_stills), 0);
  const nlohmann::json v = nlohmann::json::parse (readAll (from_video));
  const nlohmann::json s = nlohmann::json::parse (readAll (from_stills));
  ASSERT_EQ (v["frames"].size (), 3u);
  std::size_t people = 0;
  for (std::size_t n = 0; n < 3; ++n)
  {
    EXPECT_EQ (v["frames"][n]["source"], video + "#" + std::to_string (n));
    ASSERT_EQ (v["frames"][n]["people"].size (), s["frames"][n]["people"].size ()) << "frame " << n;
    for (std::size_t i = 0; i < v["frames"][n]["people"].size (); ++i)
    {
      EXPECT_EQ (v["frames"][n]["people"][i]["box"], s["frames"][n]["people"][i]["box"]);
      EXPECT_EQ (v["frames"][n]["people"][i]["landmarks"].size (), 180u);
    }
    people += v["frames"][n]["people"].size ();
  }
  EXPECT_GT (people, 0u);

  // One JSON line per frame: into a file, and streamed on standard output as each frame is done.
  const std::string lines_path = (dir / "video.jsonl").string (), streamed = (dir / "streamed.jsonl").string ();
  ASSERT_EQ (run (app + " --video " + video + " --json-lines " + lines_path), 0);
  ASSERT_EQ (std::system ((app + " --video " + video + " --json-lines - > " + streamed +
                           " 2> /dev/null")
                            .c_str ()),
             0);
  for (const std::string &file : {lines_path, streamed})
  {
    std::istringstream in (readAll (file));
    std::string line;
    std::size_t n = 0;
    for (; std::getline (in, line); ++n)
    {
      const nlohmann::json frame = nlohmann::json::parse (line);
      EXPECT_EQ (frame["source"], video + "#" + std::to_string (n)) << file;
      ASSERT_LT (n, 3u) << file;
      EXPECT_EQ (frame["people"], v["frames"][n]["people"]) << file << " frame " << n;
    }
    EXPECT_EQ (n, 3u) << file;
  }

  // --max-frames stops early; a missing video and a file that is no video are refused.
  ASSERT_EQ (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + video + " --max-frames 2 --json " + from_video), 0);
  EXPECT_EQ (nlohmann::json::parse (readAll (from_video))["frames"].size (), 2u);
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + decoded[0] + "x --json " + from_video), 0);
  const std::string text = (dir / "notes.txt").string ();
  writeAll (text, "not a video\n");
  EXPECT_NE (run (std::string (AGEX_LANDMARKS_EXECUTABLE) + " --video " + text + " --json " + from_video), 0);
  fs::remove_all (dir);
}

// A palette PNG (colour type 3), as Penn-Fudan's PedMasks are: OpenCV cannot write one, and
// reads it back as the palette's colours. Stored (uncompressed) deflate blocks keep this short.
std::uint32_t
crc32Of (const std::string &bytes)
{
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const unsigned char c : bytes)
  {
    crc ^= c;
    for (int k = 0; k < 8; ++k)
      crc = crc & 1 ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return ~crc;
}

std::string
bigEndian (std::uint32_t v)
{
  return {static_cast<char> (v >> 24), static_cast<char> (v >> 16), static_cast<char> (v >> 8), static_cast<char> (v)};
}

void
writePalettePng (const std::string &path, const cv::Mat &indices, const std::vector<cv::Vec3b> &rgb)
{
  auto chunk = [] (const std::string &type, const std::string &data) {
    return bigEndian (static_cast<std::uint32_t> (data.size ())) + type + data + bigEndian (crc32Of (type + data));
  };
  std::string raw;
  for (int y = 0; y < indices.rows; ++y)
  {
    raw += '\0';  // filter: none
    raw.append (reinterpret_cast<const char *> (indices.ptr (y)), indices.cols);
  }
  std::string zlib = "\x78\x01";
  for (std::size_t at = 0; at < raw.size (); at += 65535)
  {
    const std::size_t n = std::min<std::size_t> (65535, raw.size () - at);
    zlib += static_cast<char> (at + n == raw.size ());
    zlib += {static_cast<char> (n & 0xFF), static_cast<char> (n >> 8), static_cast<char> (~n & 0xFF),
             static_cast<char> ((~n >> 8) & 0xFF)};
    zlib += raw.substr (at, n);
  }
  std::uint32_t a = 1, b = 0;
  for (const unsigned char c : raw)
  {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  zlib += bigEndian (b << 16 | a);
  std::string palette;
  for (const cv::Vec3b &c : rgb)
    palette += {static_cast<char> (c[0]), static_cast<char> (c[1]), static_cast<char> (c[2])};
  const std::string ihdr = bigEndian (indices.cols) + bigEndian (indices.rows) + std::string ("\x08\x03\x00\x00\x00", 5);
  writeAll (path, std::string ("\x89PNG\r\n\x1a\n", 8) + chunk ("IHDR", ihdr) + chunk ("PLTE", palette) +
                    chunk ("IDAT", zlib) + chunk ("IEND", ""));
}

int
runCapturing (const std::string &command, const fs::path &dir, std::string *out, std::string *err)
{
  const std::string out_file = (dir / "stdout.txt").string (), err_file = (dir / "stderr.txt").string ();
  const int status = std::system ((command + " > " + out_file + " 2> " + err_file).c_str ());
  *out = readAll (out_file);
  *err = readAll (err_file);
  return WIFEXITED (status) ? WEXITSTATUS (status) : -1;
}

// Label maps (one person per image, excluded labels), instance masks in Penn-Fudan's layout
// (STEM_mask.png, palette PNGs), and the masks that cannot be used, each named with its reason.
TEST (LandmarkApps, AnnotateMaskFolders)
{
  const fs::path dir = tempDir ("masks");
  for (const char *sub : {"labels/images", "labels/masks", "peds/PNGImages", "peds/PedMasks"})
    fs::create_directories (dir / sub);
  const Figure f = drawFigure (cv::Size (300, 300), cv::Point2f (150, 150), 1.2f, 1.2f, 0.3f);
  cv::Mat labels = f.mask / 255 * 5;
  labels (cv::Rect (120, 146, 130, 14)).setTo (2);  // a bag across the waist, bulging to the right
  const cv::Mat photo = 40 + f.mask / 2;
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/person.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/person.png").string (), labels));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/wrong.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/wrong.png").string (), labels (cv::Rect (0, 0, 200, 200))));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/empty.png").string (), photo));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/masks/empty.png").string (), cv::Mat::zeros (300, 300, CV_8UC1)));
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/junk.png").string (), photo));
  writeAll ((dir / "labels/masks/junk.png").string (), "not a PNG");
  ASSERT_TRUE (cv::imwrite ((dir / "labels/images/nomask.png").string (), photo));
  const std::string app = AGEX_ANNOTATE_EXECUTABLE, xml = (dir / "labels.xml").string ();
  std::string out, err;
  ASSERT_EQ (runCapturing (app + " masks --images " + (dir / "labels/images").string () + " --masks " +
                             (dir / "labels/masks").string () + " --labels-excluded 2,33,56 --out " + xml,
                           dir, &out, &err),
             0)
    << err;
  EXPECT_NE (out.find ("1 images, 1 people outlined, 0 ignore boxes, 4 images left out"), std::string::npos) << out;
  for (const char *expected : {"wrong.png: left out: mask of another size than its image", "empty.png: left out: empty mask",
                               "junk.png: left out: unreadable mask", "nomask.png: left out: no mask"})
    EXPECT_NE (err.find (expected), std::string::npos) << expected << "\n" << err;
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  ASSERT_EQ (d.images[0].boxes.size (), 1u);
  const agex::ImglabBox &box = d.images[0].boxes[0];
  ASSERT_EQ (box.parts.size (), 180u);
  // The bag split the body; the outline still reaches the feet, and leaves the bag's bulge out.
  EXPECT_LT (cv::norm (box.parts.at ("072") - f.foot_left), 8.0) << box.parts.at ("072");
  EXPECT_LT (cv::norm (box.parts.at ("108") - f.foot_right), 8.0) << box.parts.at ("108");
  for (const auto &[name, p] : box.parts)
    EXPECT_LT (p.x, 215.f) << name << " " << p;

  // Penn-Fudan: PNGImages/X.png with PedMasks/X_mask.png, two people and one too small.
  cv::Mat peds = cv::Mat::zeros (300, 400, CV_8UC1);
  const Figure a = drawFigure (cv::Size (400, 300), cv::Point2f (100, 150), 1.2f, 0.6f, 0.3f);
  const Figure b = drawFigure (cv::Size (400, 300), cv::Point2f (290, 150), 1.2f, 1.1f, 0.3f);
  peds.setTo (1, a.mask);
  peds.setTo (2, b.mask);
  cv::rectangle (peds, cv::Rect (380, 10, 6, 20), 3, cv::FILLED);
  writePalettePng ((dir / "peds/PedMasks/FudanPed00001_mask.png").string (), peds,
                   {{0, 0, 0}, {128, 0, 0}, {0, 128, 0}, {128, 128, 0}, {0, 0, 0}});
  ASSERT_TRUE (cv::imwrite ((dir / "peds/PNGImages/FudanPed00001.png").string (), cv::Mat (40 + (a.mask | b.mask) / 2)));
  const std::string peds_xml = (dir / "peds.xml").string ();
  const std::string peds_command = app + " masks --images " + (dir / "peds/PNGImages").string () + " --masks " +
                                   (dir / "peds/PedMasks").string () + " --instances --out " + peds_xml;
  ASSERT_EQ (runCapturing (peds_command, dir, &out, &err), 0) << err;
  EXPECT_NE (err.find ("FudanPed00001.png: person 3: ignore box: shorter than 48 px"), std::string::npos) << err;
  const agex::ImglabDataset p = agex::readImglabDataset (peds_xml);
  ASSERT_EQ (p.images.size (), 1u);
  ASSERT_EQ (p.images[0].boxes.size (), 3u);
  EXPECT_EQ (p.images[0].boxes[0].parts.size (), 180u);
  EXPECT_LT (cv::norm (p.images[0].boxes[0].parts.at ("000") - a.head_top), 4.0);  // value 1 is the left one
  EXPECT_LT (cv::norm (p.images[0].boxes[1].parts.at ("000") - b.head_top), 4.0);
  EXPECT_TRUE (p.images[0].boxes[2].ignore);
  // Flags that contradict each other, and names that are not there.
  EXPECT_EQ (runCapturing (peds_command + " --labels-excluded 2", dir, &out, &err), 1);
  EXPECT_NE (err.find ("--labels-excluded applies to label maps"), std::string::npos) << err;
  EXPECT_EQ (runCapturing (peds_command + " --only FudanPed00002.png", dir, &out, &err), 1);
  EXPECT_EQ (runCapturing (peds_command + " --skip FudanPed00001.png", dir, &out, &err), 1);  // nothing left
  EXPECT_EQ (runCapturing (app + " masks --images " + (dir / "labels/images").string () + " --masks " +
                             (dir / "labels/masks").string () + " --labels-excluded 2,x --out " + xml,
                           dir, &out, &err),
             1);
  EXPECT_NE (err.find ("'x' is not a label"), std::string::npos) << err;
  fs::remove_all (dir);
}

// COCO RLE segmentations, compressed and as count lists, beside polygons; crowd annotations
// become ignore boxes and other categories are left out; the summary says why.
TEST (LandmarkApps, AnnotateCocoRleMasks)
{
  const fs::path dir = tempDir ("coco_rle");
  const cv::Size size (420, 300);
  std::vector<Figure> figures;
  cv::Mat all = cv::Mat::zeros (size, CV_8UC1);
  for (const float x : {80.f, 210.f, 340.f})
  {
    figures.push_back (drawFigure (size, cv::Point2f (x, 150), 1.1f, 0.9f, 0.3f));
    all |= figures.back ().mask;
  }
  ASSERT_TRUE (cv::imwrite ((dir / "people.png").string (), cv::Mat (40 + all / 2)));
  auto bbox = [] (const cv::Mat &mask) {
    const cv::Rect r = cv::boundingRect (mask);
    return nlohmann::json::array ({r.x, r.y, r.width, r.height});
  };
  const std::vector<std::uint32_t> counts0 = agex::cocoRleFromMask (figures[0].mask);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours (figures[2].mask.clone (), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  std::vector<float> polygon;
  for (const cv::Point &q : contours[0])
    polygon.insert (polygon.end (), {static_cast<float> (q.x), static_cast<float> (q.y)});
  cv::Mat crowd = cv::Mat::zeros (size, CV_8UC1);
  crowd (cv::Rect (5, 5, 60, 40)).setTo (255);
  nlohmann::json coco = {
    {"images", {{{"id", 1}, {"file_name", "people.png"}, {"width", size.width}, {"height", size.height}}}},
    {"categories", {{{"id", 1}, {"name", "person"}}, {{"id", 18}, {"name", "dog"}}}},
    {"annotations",
     {{{"id", 10}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[0].mask)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleString (counts0)}}}},
      {{"id", 11}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[1].mask)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleFromMask (figures[1].mask)}}}},
      {{"id", 12}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 0}, {"bbox", bbox (figures[2].mask)},
       {"segmentation", {polygon}}},
      {{"id", 13}, {"image_id", 1}, {"category_id", 1}, {"iscrowd", 1}, {"bbox", bbox (crowd)},
       {"segmentation", {{"size", {size.height, size.width}}, {"counts", agex::cocoRleFromMask (crowd)}}}},
      {{"id", 14}, {"image_id", 1}, {"category_id", 18}, {"iscrowd", 0}, {"bbox", {1, 1, 5, 5}}, {"segmentation", {}}}}}};
  const std::string json = (dir / "coco.json").string (), xml = (dir / "coco.xml").string ();
  writeAll (json, coco.dump ());
  const std::string command = std::string (AGEX_ANNOTATE_EXECUTABLE) + " coco --json " + json + " --images " +
                              dir.string () + " --out " + xml;
  std::string out, err;
  ASSERT_EQ (runCapturing (command, dir, &out, &err), 0) << err;
  EXPECT_NE (out.find ("1 images, 3 people outlined, 1 ignore boxes (crowd annotation (iscrowd): 1)"), std::string::npos)
    << out;
  EXPECT_NE (err.find ("person 13: ignore box: crowd annotation (iscrowd)"), std::string::npos) << err;
  const agex::ImglabDataset d = agex::readImglabDataset (xml);
  ASSERT_EQ (d.images.size (), 1u);
  ASSERT_EQ (d.images[0].boxes.size (), 4u);
  for (int i = 0; i < 3; ++i)
  {
    // The same outline as the mask itself gives.
    const agex::ContourAnnotation direct = agex::annotateContour (figures[i].mask, agex::ContourAnchors ());
    ASSERT_TRUE (direct.ok);
    EXPECT_LT (cv::norm (d.images[0].boxes[i].parts.at ("000") - direct.landmarks[0]), 1.5) << i;
    EXPECT_LT (cv::norm (d.images[0].boxes[i].parts.at ("090") - direct.landmarks[90]), 1.5) << i;
  }
  EXPECT_TRUE (d.images[0].boxes[3].ignore);
  // An RLE of another size than the image, and a damaged RLE string, name the annotation.
  coco["annotations"][0]["segmentation"]["size"] = {200, size.width};
  writeAll (json, coco.dump ());
  EXPECT_EQ (runCapturing (command, dir, &out, &err), 1);
  EXPECT_NE (err.find ("people.png: person 10: the RLE mask is 420x200"), std::string::npos) << err;
  coco["annotations"][0]["segmentation"] = {{"size", {size.height, size.width}}, {"counts", "25 4"}};
  writeAll (json, coco.dump ());
  EXPECT_EQ (runCapturing (command, dir, &out, &err), 1);
  EXPECT_NE (err.find ("person 10: character ' ' at 2"), std::string::npos) << err;
  fs::remove_all (dir);
}
#endif

#if defined(AGEX_ANNOTATE_EXECUTABLE) && defined(AGEX_LANDMARKS_EVAL_EXECUTABLE)
// The evaluation reports detection AP, false detections per image and the contour distance
// per box height; a deeply nested dataset is refused by name (it crashed the app before).
TEST (LandmarkApps, EvalReportsDetectionAndRefusesDeepFiles)
{
  const fs::path dir = tempDir ("eval");
  agex::ImglabDataset dataset;
  std::vector<double> box_heights;
  for (int i = 0; i < 3; ++i)
  {
    const Figure f = drawFigure (cv::Size (260, 260), cv::Point2f (120.f + 10 * i, 130), 1.2f, 0.4f + 0.3f * i, 0.3f);
    const std::string image = "figure" + std::to_string (i) + ".png";
    ASSERT_TRUE (cv::imwrite ((dir / image).string (), cv::Mat (40 + f.mask / 2)));
    const agex::ContourAnnotation a = agex::annotateContour (f.mask, agex::ContourAnchors ());
    ASSERT_TRUE (a.ok);
    agex::ImglabImage entry;
    entry.file = image;
    agex::ImglabBox box;
    box.rect = a.box;
    box_heights.push_back (a.box.height);
    for (int k = 0; k < agex::kContourLandmarkCount; ++k)
      box.parts[agex::contourLandmarkName (k)] = a.landmarks[k];
    entry.boxes.push_back (box);
    dataset.images.push_back (entry);
  }
  const std::string xml = (dir / "figures.xml").string (), json = (dir / "eval.json").string ();
  agex::writeImglabDataset (xml, dataset);
  const std::string app = AGEX_LANDMARKS_EVAL_EXECUTABLE;
  std::string out, err;
  ASSERT_EQ (runCapturing (app + " --dataset " + xml + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --opencv-detector --json " + json,
                           dir, &out, &err),
             0)
    << err;
  const nlohmann::json doc = nlohmann::json::parse (readAll (json));
  EXPECT_EQ (doc["people"], 3);
  EXPECT_EQ (doc["detection_people"], 3);
  for (const char *key : {"detection_ap", "detection_recall", "false_detections_per_image", "mean_contour_distance_px",
                          "mean_contour_distance_box_height", "mean_error_box_height"})
    EXPECT_TRUE (doc[key].is_number ()) << key << ": " << doc[key];
  // The mean of distance / box height lies between the mean distance over the largest and over
  // the smallest box.
  const double px = doc["mean_contour_distance_px"], per_box = doc["mean_contour_distance_box_height"];
  EXPECT_GT (px, 0.0);
  EXPECT_GE (per_box, px / *std::max_element (box_heights.begin (), box_heights.end ()) - 1e-9);
  EXPECT_LE (per_box, px / *std::min_element (box_heights.begin (), box_heights.end ()) + 1e-9);
  ASSERT_EQ (runCapturing (app + " --dataset " + xml + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --no-detector --json " + json,
                           dir, &out, &err),
             0);
  EXPECT_TRUE (nlohmann::json::parse (readAll (json))["detection_ap"].is_null ());

  std::string deep = "<dataset>\n<images>\n";
  for (int i = 0; i < 50000; ++i)
    deep += "<image file='a.png'>";
  writeAll ((dir / "deep.xml").string (), deep);
  EXPECT_EQ (runCapturing (app + " --dataset " + (dir / "deep.xml").string () + " --model " + AGEX_SOURCE_DIR +
                             "/data/models/agex_contour_landmarks.dat --no-detector",
                           dir, &out, &err),
             1);  // a stack overflow was a signal, not exit code 1
  EXPECT_NE (err.find ((dir / "deep.xml").string () + ": line 3: elements nested more than 64 deep"), std::string::npos)
    << err;
  fs::remove_all (dir);
}
#endif
}  // namespace

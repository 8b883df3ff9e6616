// The 2D contour-landmark module: imglab XML round trip and bad files, automatic
// annotation of hand-built masks (count, on the outline, start, direction, anchors,
// mirror symmetry), a small shape-predictor training run on synthetic figures, the people
// detector, and the detection AP the evaluation reports. (The apps run as built:
// test/apps/test_landmark_apps.cpp.)

#include <agex/common/statistics.h>
#include <agex/landmarks/annotation_sources.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/landmark_evaluation.h>
#include <agex/landmarks/people_detector.h>
#include <agex/landmarks/person_masks.h>

#include "landmarks/figures.h"
#include "test_support.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <thread>

namespace
{
using agex_test::readAll;
using agex_test::writeAll;
using namespace landmark_test;  // drawFigure, Figure, tempDir
namespace fs = std::filesystem;

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
  // Numbers beyond their type: 1e300 is infinite as a float, 4294967643 is 347 as an int.
  const std::string box = "<dataset><images><image file='a'>\n<box top='1' left='2' width='30' height='40'>";
  expect_error (box + "<part name='p' x='1e300' y='5'/></box></image></images></dataset>",
                "line 2: attribute 'x' of <part> is 1e300, not a pixel coordinate");
  expect_error (box + "<part name='p' x='5' y='-3e9'/></box></image></images></dataset>", "'y' of <part> is -3e9");
  expect_error ("<dataset><images><image file='a'><box top='1' left='2' width='4294967643' height='4'/></image>"
                "</images></dataset>",
                "attribute 'width' of <box> is 4294967643, not a pixel size");
  expect_error ("<dataset><images><image file='a'><box top='1' left='1e300' width='4' height='4'/></image>"
                "</images></dataset>",
                "attribute 'left' of <box> is 1e300");
  writeAll (path, box + "<part name='p' x='-1000000' y='999999.5'/></box></image></images></dataset>");
  EXPECT_EQ (agex::readImglabDataset (path).images[0].boxes[0].parts.at ("p").x, -1e6f);
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

// COCO numbers are taken into their real type with a range check: an RLE count plus 2^32,
// fractional counts or sizes, and vertices at 1e300 or 3e9 are refused, not wrapped or cast.
TEST (CocoAnnotations, NumbersOutOfTheirTypeAreRefused)
{
  const fs::path dir = tempDir ("coco_numbers");
  const std::string path = (dir / "coco.json").string ();
  const std::string image = R"({"images": [{"id": 1, "file_name": "a.png", "width": 4, "height": 3}], )";
  auto person = [&] (const std::string &annotation) {
    writeAll (path, image + R"("annotations": [{"id": 7, "image_id": 1, "bbox": [0, 0, 4, 3], )" + annotation + "}]}");
    return agex::readCocoPeople (path).at (0).people.at (0);
  };
  auto error = [&] (auto fn) {
    try
    {
      fn ();
    }
    catch (const std::runtime_error &e)
    {
      return std::string (e.what ());
    }
    return std::string ();
  };
  const cv::Size size (4, 3);
  // The right counts, then the same plus 2^32, fractional, and a fractional size.
  EXPECT_EQ (cv::countNonZero (agex::cocoPersonMask (person (R"("segmentation": {"counts": [2, 5, 4, 1], "size": [3, 4]})"),
                                                     size, "p")),
             6);
  for (const auto &[segmentation, expect] : std::vector<std::pair<std::string, std::string>> {
         {R"({"counts": [2, 4294967301, 4, 1], "size": [3, 4]})", "p: RLE count 1 4294967301 is not a whole number in [0, 12]"},
         {R"({"counts": [2, 5.5, 3.5, 1], "size": [3, 4]})", "RLE count 1 5.5 is not a whole number"},
         {R"({"counts": [2, 5, 4, 1], "size": [3.5, 4]})", "RLE size[0] (height) 3.5 is not a whole number"},
         {R"([[0, 0, 1e300, 0, 2, 2]])", "polygon vertex coordinate 1e+300 is not a pixel coordinate"},
         {R"([[0, 0, 3000000000, 0, 2, 2]])", "polygon vertex coordinate 3000000000 is not a pixel coordinate"},
         {R"([[0, 0, -3e9, 0, 2, 2]])", "polygon vertex coordinate -3000000000.0 is not a pixel coordinate"}})
  {
    const agex::CocoPerson p = person ("\"segmentation\": " + segmentation);
    const std::string message = error ([&] { agex::cocoPersonMask (p, size, "p"); });
    EXPECT_NE (message.find (expect), std::string::npos) << segmentation << ": " << message;
  }
  // Keypoints and ids, refused when the file is read, naming it and the annotation.
  for (const auto &[annotation, expect] : std::vector<std::pair<std::string, std::string>> {
         {R"("keypoints": [1e300, 2, 2])", "annotation 7: keypoint x 1e+300 is not a pixel coordinate"},
         {R"("keypoints": [1, 2, 1.5])", "annotation 7: keypoint visibility 1.5 is not a whole number in [0, 2]"}})
  {
    const std::string &field = annotation;  // a structured binding cannot be captured in C++17
    const std::string message = error ([&] { person (field); });
    EXPECT_NE (message.find (path + ": " + expect), std::string::npos) << annotation << ": " << message;
  }
  writeAll (path, R"({"images": [{"id": 1.5, "file_name": "a.png"}], "annotations": []})");
  EXPECT_NE (error ([&] { agex::readCocoPeople (path); }).find ("id 1.5 is not a whole number"), std::string::npos);
  fs::remove_all (dir);
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
/** Figures on noise, one per 240x240 image, drawn by rng: the image and the figure's box. */
cv::Mat
noisyFigure (std::mt19937 &rng, cv::Rect *box)
{
  std::uniform_real_distribution<float> arm (-0.5f, 1.2f), legs (0.15f, 0.45f), where (70.f, 170.f);
  const Figure f = drawFigure (cv::Size (240, 240), cv::Point2f (where (rng), 115), 0.9f, arm (rng), legs (rng));
  *box = agex::annotateContour (f.mask, agex::ContourAnchors ()).box;
  cv::Mat noise (f.mask.size (), CV_8UC1);
  cv::randu (noise, 0, 60);
  return cv::Mat (noise + f.mask * 0.7);
}

/** A 64x64-window detector trained on 8 noisy figures drawn by rng. */
agex::PeopleDetector
trainOnNoisyFigures (std::mt19937 &rng, double c)
{
  std::vector<cv::Mat> images;
  std::vector<std::vector<cv::Rect>> boxes;
  for (int i = 0; i < 8; ++i)
  {
    cv::Rect box;
    images.push_back (noisyFigure (rng, &box));
    boxes.push_back ({box});
  }
  agex::PeopleDetectorTrainingParams params;
  params.window_width = params.window_height = 64;
  params.num_threads = 2;
  params.c = c;
  return agex::PeopleDetector::train (images, boxes, params);
}

TEST (PeopleDetector, TrainsOnSyntheticFiguresAndRoundTrips)
{
  std::mt19937 rng (3);
  const agex::PeopleDetector detector = trainOnNoisyFigures (rng, 20.0);
  EXPECT_FALSE (detector.isOpenCvDefault ());
  cv::Rect truth;
  const cv::Mat test = noisyFigure (rng, &truth);
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
  EXPECT_THROW (agex::PeopleDetector::train ({}, {}, agex::PeopleDetectorTrainingParams ()), std::invalid_argument);
  fs::remove_all (dir);
}

// One detector, several threads: each finds what one thread alone finds (dlib's own detector
// call loads the image into its scanner; agex scans with evaluate_detectors, which does not).
TEST (PeopleDetector, OneDetectorServesSeveralThreads)
{
  std::mt19937 rng (11);
  const agex::PeopleDetector detector = trainOnNoisyFigures (rng, 20.0);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i)
  {
    cv::Rect box;
    images.push_back (noisyFigure (rng, &box));
  }
  std::vector<std::vector<agex::PersonDetection>> expected;
  for (const cv::Mat &image : images)
    expected.push_back (detector.detect (image, -0.8));
  std::vector<std::vector<std::vector<agex::PersonDetection>>> found (images.size ());
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < images.size (); ++t)
    threads.emplace_back ([&, t] {
      for (int round = 0; round < 20; ++round)
        found[t].push_back (detector.detect (images[t], -0.8));
    });
  for (auto &thread : threads)
    thread.join ();
  for (std::size_t t = 0; t < images.size (); ++t)
    for (const auto &run : found[t])
    {
      ASSERT_EQ (run.size (), expected[t].size ()) << "image " << t;
      for (std::size_t i = 0; i < run.size (); ++i)
      {
        EXPECT_EQ (run[i].box, expected[t][i].box);
        EXPECT_EQ (run[i].score, expected[t][i].score);
      }
    }
}

// Two different detectors that scan alike share one HOG pyramid in an ensemble; what the
// ensemble keeps is what each finds alone at its own threshold, merged by one suppression.
TEST (PeopleDetector, SharedPyramidFindsWhatEachMemberFindsAlone)
{
  std::mt19937 rng (7);
  const fs::path dir = tempDir ("shared_pyramid");
  const std::string a_path = (dir / "a.svm").string (), b_path = (dir / "b.svm").string ();
  trainOnNoisyFigures (rng, 20.0).save (a_path);
  trainOnNoisyFigures (rng, 2.0).save (b_path);
  cv::Mat image (240, 480, CV_8UC1);
  cv::Rect left, right;
  noisyFigure (rng, &left).copyTo (image (cv::Rect (0, 0, 240, 240)));
  noisyFigure (rng, &right).copyTo (image (cv::Rect (240, 0, 240, 240)));
  std::vector<agex::PeopleDetector> members;
  members.push_back (agex::PeopleDetector::load (a_path));
  members.push_back (agex::PeopleDetector::load (b_path));
  // Member a finds the two figures above -0.6 and many windows near -1; b runs 0.6 lower.
  const double threshold = -0.6, offset_b = -0.6;
  const auto shared = agex::PeopleDetector::combine (std::move (members), {0.0, offset_b}).detect (image, threshold);

  std::vector<agex::PersonDetection> alone = agex::PeopleDetector::load (a_path).detect (image, threshold);
  for (agex::PersonDetection d : agex::PeopleDetector::load (b_path).detect (image, threshold + offset_b))
  {
    d.score -= offset_b;
    alone.push_back (d);
  }
  std::stable_sort (alone.begin (), alone.end (),
                    [] (const agex::PersonDetection &x, const agex::PersonDetection &y) { return x.score > y.score; });
  std::vector<agex::PersonDetection> expected;
  for (const agex::PersonDetection &d : alone)
  {
    const bool same = std::any_of (expected.begin (), expected.end (), [&] (const agex::PersonDetection &k) {
      const double covered = static_cast<double> ((k.box & d.box).area ()) / std::min (k.box.area (), d.box.area ());
      return agex::boxIoU (k.box, d.box) > 0.5 || covered > 0.95;
    });
    if (!same)
      expected.push_back (d);
  }
  ASSERT_GE (expected.size (), 2u) << "both figures should be found";
  ASSERT_EQ (shared.size (), expected.size ());
  for (std::size_t i = 0; i < shared.size (); ++i)
  {
    EXPECT_EQ (shared[i].box, expected[i].box) << i;
    EXPECT_DOUBLE_EQ (shared[i].score, expected[i].score) << i;
  }
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

// An ensemble of a detector with itself is the detector: the duplicates are suppressed. A
// member's offset moves its threshold, and its scores by as much the other way.
TEST (PeopleDetector, EnsembleMergesItsMembersDetections)
{
  const cv::Mat image = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (image.empty ());
  const std::string bundled = std::string (AGEX_SOURCE_DIR) + "/data/models/agex_people_detector.svm";
  const auto alone = agex::PeopleDetector::load (bundled).detect (image, -0.5);
  ASSERT_FALSE (alone.empty ());
  std::vector<agex::PeopleDetector> twins;
  twins.push_back (agex::PeopleDetector::load (bundled));
  twins.push_back (agex::PeopleDetector::load (bundled));
  const auto both = agex::PeopleDetector::combine (std::move (twins), {0.0, 0.0}).detect (image, -0.5);
  ASSERT_EQ (both.size (), alone.size ());
  for (std::size_t i = 0; i < both.size (); ++i)
  {
    EXPECT_EQ (both[i].box, alone[i].box);
    EXPECT_DOUBLE_EQ (both[i].score, alone[i].score);
  }
  std::vector<agex::PeopleDetector> one;
  one.push_back (agex::PeopleDetector::load (bundled));
  const auto shifted = agex::PeopleDetector::combine (std::move (one), {-0.3}).detect (image, -0.2);
  ASSERT_EQ (shifted.size (), alone.size ());  // threshold -0.2 + offset -0.3: the -0.5 above
  for (std::size_t i = 0; i < shifted.size (); ++i)
    EXPECT_NEAR (shifted[i].score, alone[i].score + 0.3, 1e-12);
  EXPECT_THROW (agex::PeopleDetector::combine ({}, {}), std::invalid_argument);
  std::vector<agex::PeopleDetector> bad;
  bad.push_back (agex::PeopleDetector::openCvDefault ());
  EXPECT_THROW (agex::PeopleDetector::combine (std::move (bad), {6.0}), std::invalid_argument);
  std::vector<agex::PeopleDetector> saved;
  saved.push_back (agex::PeopleDetector::openCvDefault ());
  EXPECT_THROW (agex::PeopleDetector::combine (std::move (saved), {0.0}).save ("/nonexistent/x.svm"), std::logic_error);
}

/** The members' offsets an ensemble's description lists ("..., offset 0.200000; ..."); none
  * for a single detector. */
std::vector<double>
memberOffsets (const agex::PeopleDetector &detector)
{
  std::vector<double> offsets;
  const std::string text = detector.description ();
  for (std::size_t at = text.find ("offset "); at != std::string::npos; at = text.find ("offset ", at + 1))
    offsets.push_back (std::stod (text.substr (at + 7)));
  return offsets;
}

// An ensemble written to a file is the same ensemble read back: members, offsets, detections.
// Damaged ensemble files are refused naming the file; an ensemble holds 1 to 8 members. (The
// bundled detector is an ensemble itself: its members join, their offsets added.)
TEST (PeopleDetector, EnsembleFileKeepsItsMembersAndOffsets)
{
  const cv::Mat image = cv::imread (std::string (AGEX_SOURCE_DIR) + "/data/images/five_people.jpg");
  ASSERT_FALSE (image.empty ());
  const std::string bundled = std::string (AGEX_SOURCE_DIR) + "/data/models/agex_people_detector.svm";
  std::vector<agex::PeopleDetector> members;
  members.push_back (agex::PeopleDetector::load (bundled));
  members.push_back (agex::PeopleDetector::load (bundled));
  const agex::PeopleDetector ensemble = agex::PeopleDetector::combine (std::move (members), {0.0, -0.4});
  const auto expected = ensemble.detect (image, -0.3);
  ASSERT_FALSE (expected.empty ());

  const fs::path dir = tempDir ("ensemble");
  const std::string path = (dir / "both.svm").string ();
  ensemble.save (path);
  const agex::PeopleDetector loaded = agex::PeopleDetector::load (path);
  EXPECT_EQ (loaded.description (), ensemble.description ());
  const auto found = loaded.detect (image, -0.3);
  ASSERT_EQ (found.size (), expected.size ());
  for (std::size_t i = 0; i < found.size (); ++i)
  {
    EXPECT_EQ (found[i].box, expected[i].box);
    EXPECT_DOUBLE_EQ (found[i].score, expected[i].score);
  }
  // The members share one HOG pyramid, each at its own threshold: the one at -0.4 finds what
  // the detector alone finds at -0.7, 0.4 higher, and wins over its twin's copy of each box.
  const auto at_07 = agex::PeopleDetector::load (bundled).detect (image, -0.7);
  EXPECT_GT (found.size (), agex::PeopleDetector::load (bundled).detect (image, -0.3).size ());
  ASSERT_EQ (found.size (), at_07.size ());
  for (std::size_t i = 0; i < found.size (); ++i)
  {
    EXPECT_EQ (found[i].box, at_07[i].box);
    EXPECT_NEAR (found[i].score, at_07[i].score + 0.4, 1e-12);
  }

  const std::vector<double> bundled_offsets = memberOffsets (agex::PeopleDetector::load (bundled));
  const std::size_t per_copy = std::max<std::size_t> (1, bundled_offsets.size ());
  const std::vector<double> offsets = memberOffsets (loaded);
  ASSERT_EQ (offsets.size (), 2 * per_copy);
  for (std::size_t i = 0; i < per_copy; ++i)
  {
    const double own = bundled_offsets.empty () ? 0.0 : bundled_offsets[i];
    EXPECT_NEAR (offsets[i], own, 1e-6);
    EXPECT_NEAR (offsets[per_copy + i], own - 0.4, 1e-6);
  }

  // The member count follows the header line as dlib's integer: a length byte, then the value.
  const std::string bytes = readAll (path);
  const std::size_t count_at = bytes.find ('\n') + 1;
  ASSERT_EQ (bytes.substr (count_at, 2), std::string ("\x01", 1) + static_cast<char> (2 * per_copy));
  const auto expectRefused = [&] (const std::string &name, const std::string &content, const std::string &why) {
    const std::string damaged = (dir / name).string ();
    writeAll (damaged, content);
    try
    {
      agex::PeopleDetector::load (damaged);
      ADD_FAILURE () << name << " loaded";
    }
    catch (const std::runtime_error &e)
    {
      EXPECT_NE (std::string (e.what ()).find (damaged), std::string::npos) << e.what ();
      EXPECT_NE (std::string (e.what ()).find (why), std::string::npos) << e.what ();
    }
  };
  std::string none = bytes, nine = bytes;
  none[count_at + 1] = '\0';
  nine[count_at + 1] = '\x09';
  expectRefused ("none.svm", none, "0 members");
  expectRefused ("nine.svm", nine, "9 members");
  expectRefused ("cut.svm", bytes.substr (0, bytes.size () / 2), "damaged");
  expectRefused ("header.svm", "agex_people_detector_fhog_ensemble 1\n", "damaged");
  expectRefused ("longer.svm", bytes + "x", "bytes after the last detector");
  try
  {
    agex::PeopleDetector::load (dir.string ());
    ADD_FAILURE () << "a directory loaded";
  }
  catch (const std::runtime_error &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("not a regular file"), std::string::npos) << e.what ();
  }
  // Damage anywhere (sizes, settings, weights) is refused or loads as some detector, never a
  // crash, a read past a buffer (the sanitizer build checks) or an allocation of what a size
  // claims: the decoder checks dlib's sizes before dlib allocates them.
  std::mt19937 rng (35);
  const std::string damaged_path = (dir / "damaged.svm").string ();
  for (int trial = 0; trial < 300; ++trial)
  {
    std::string damaged = bytes;
    const std::size_t at = count_at + rng () % std::min<std::size_t> (bytes.size () - count_at, 400);
    damaged[at] = static_cast<char> (rng ());
    writeAll (damaged_path, damaged);
    try
    {
      const agex::PeopleDetector detector = agex::PeopleDetector::load (damaged_path);
      detector.detect (cv::Mat (64, 64, CV_8UC1, cv::Scalar (90)));
    }
    catch (const std::runtime_error &e)
    {
      EXPECT_NE (std::string (e.what ()).find (damaged_path), std::string::npos) << e.what ();
    }
  }

  std::vector<agex::PeopleDetector> many;
  for (int i = 0; i < 9; ++i)
    many.push_back (agex::PeopleDetector::load (bundled));
  EXPECT_THROW (agex::PeopleDetector::combine (std::move (many), std::vector<double> (9, 0.0)), std::invalid_argument);
  // An ensemble as a member gives its members, offsets added; saved as one level.
  std::vector<agex::PeopleDetector> nested;
  nested.push_back (agex::PeopleDetector::load (path));
  nested.push_back (agex::PeopleDetector::load (bundled));
  const agex::PeopleDetector three = agex::PeopleDetector::combine (std::move (nested), {0.2, 0.0});
  const std::string text = three.description ();
  const std::vector<double> three_offsets = memberOffsets (three);
  ASSERT_EQ (three_offsets.size (), 3 * per_copy) << text;
  for (std::size_t i = 0; i < 2 * per_copy; ++i)
    EXPECT_NEAR (three_offsets[i], offsets[i] + 0.2, 1e-6) << text;
  const std::string three_path = (dir / "three.svm").string ();
  three.save (three_path);
  EXPECT_EQ (agex::PeopleDetector::load (three_path).description (), text);
  std::vector<agex::PeopleDetector> too_low;
  too_low.push_back (agex::PeopleDetector::load (path));
  EXPECT_THROW (agex::PeopleDetector::combine (std::move (too_low), {-4.8}), std::invalid_argument);  // -0.4 - 4.8 and less
  std::vector<agex::PeopleDetector> with_opencv;
  with_opencv.push_back (agex::PeopleDetector::load (bundled));
  with_opencv.push_back (agex::PeopleDetector::openCvDefault ());
  EXPECT_THROW (agex::PeopleDetector::combine (std::move (with_opencv), {0.0, 0.0}).save (path), std::logic_error);
  EXPECT_EQ (readAll (path), bytes) << "a refused save leaves the file as it was";
  fs::remove_all (dir);
}

// The loss per missed person is bounded: 0 would make every person free to miss, a huge value
// every false detection free.
TEST (PeopleDetector, LossPerMissedPersonOutsideItsRangeIsRefused)
{
  const cv::Mat image (128, 128, CV_8UC1, cv::Scalar (9));
  const std::vector<std::vector<cv::Rect>> boxes{{cv::Rect (32, 16, 48, 96)}};
  for (const double loss : {0.0, -1.0, 1001.0, std::numeric_limits<double>::quiet_NaN ()})
  {
    agex::PeopleDetectorTrainingParams params;
    params.loss_per_missed_target = loss;
    params.num_threads = 1;
    try
    {
      agex::PeopleDetector::train ({image}, boxes, params);
      ADD_FAILURE () << "trained with the loss per missed person " << loss;
    }
    catch (const std::invalid_argument &e)
    {
      EXPECT_NE (std::string (e.what ()).find ("missed person"), std::string::npos) << e.what ();
    }
  }
}

// Recall at 0.1 false detections per image by hand: 10 images allow 1 false detection, so the
// walk down the scores keeps 0.9, 0.7 and the tie at 0.6 (a hit and the first false one: 3 of
// 4 found) and stops at the second false one (0.5). Allowing none, the tie at 0.6 goes too.
TEST (LandmarkEvaluation, RecallAtFalseDetectionsByHand)
{
  double at = 0;
  const std::vector<std::pair<double, bool>> scored{{0.9, true}, {0.5, false}, {0.6, false}, {0.7, true}, {0.6, true}, {0.4, true}};
  EXPECT_NEAR (agex::recallAtFalseDetections (scored, 4, 10, 0.1, &at), 0.75, 1e-12);
  EXPECT_DOUBLE_EQ (at, 0.6);
  EXPECT_NEAR (agex::recallAtFalseDetections (scored, 4, 10, 0.0, &at), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ (at, 0.7);
  EXPECT_NEAR (agex::recallAtFalseDetections ({{0.3, false}}, 4, 1, 0.5, &at), 0.0, 1e-12);
  EXPECT_TRUE (std::isinf (at));
  EXPECT_EQ (agex::recallAtFalseDetections (scored, 0, 10, 0.1), 0.0);
}

// All-point interpolated AP by hand: hits at ranks 1 and 3 of 3 truths: precision 1 up to
// recall 1/3, then 2/3 up to recall 2/3 (the 0.5 at rank 2 is lifted to rank 3's 2/3).
TEST (LandmarkEvaluation, AveragePrecisionByHand)
{
  EXPECT_NEAR (agex::averagePrecision ({{0.9, true}, {0.8, false}, {0.7, true}}, 3), 1.0 / 3 + 2.0 / 9, 1e-12);
  EXPECT_NEAR (agex::averagePrecision ({{0.7, true}, {0.9, true}}, 2), 1.0, 1e-12);  // sorted by score
  EXPECT_DOUBLE_EQ (agex::averagePrecision ({{0.9, false}}, 1), 0.0);
  EXPECT_DOUBLE_EQ (agex::averagePrecision ({}, 0), 0.0);
}
}  // namespace

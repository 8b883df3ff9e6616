// The 2D module on real people: the Clothing Co-Parsing photos of ../shared (label-map masks).
// A shape predictor trained on a few CCP people beats the mean shape on others, and the
// bundled models find and outline people in CCP photos held out of their training.

#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/people_detector.h>
#include <agex/landmarks/person_masks.h>

#include "test_support.h"

#include <opencv2/imgcodecs.hpp>

namespace
{
// The photos doc/landmarks.md names as held out of the bundled models' training.
const std::vector<std::string> kHeldOut{"0090", "0180", "0270", "0360", "0450", "0540", "0630", "0720", "0810", "0900"};

struct CcpPerson
{
  cv::Mat grey;
  agex::ContourAnnotation annotation;
};

CcpPerson
ccpPerson (const std::string &id)
{
  const std::string dir = agex_test::sharedData ("people2d/ccp/");
  CcpPerson person;
  person.grey = cv::imread (dir + "photos/" + id + ".jpg", cv::IMREAD_GRAYSCALE);
  const cv::Mat labels = cv::imread (dir + "masks/" + id + ".png", cv::IMREAD_UNCHANGED);
  if (person.grey.empty () || labels.empty ())
    throw std::runtime_error ("CCP photo or mask " + id + " cannot be read");
  const agex::LabelMapPerson mask = agex::personFromLabelMap (labels, {2, 33, 56});
  if (!mask.problem.empty ())
    throw std::runtime_error ("CCP mask " + id + ": " + mask.problem);
  person.annotation = agex::annotateContour (mask.mask, agex::ContourAnchors ());
  if (!person.annotation.ok)
    throw std::runtime_error ("CCP mask " + id + ": " + person.annotation.problem);
  return person;
}

std::string
ccpId (int n)
{
  return cv::format ("%04d", n);
}

double
meanError (const std::vector<cv::Point2f> &a, const std::vector<cv::Point2f> &b)
{
  double sum = 0;
  for (std::size_t i = 0; i < a.size (); ++i)
    sum += cv::norm (a[i] - b[i]);
  return sum / a.size ();
}

TEST (CcpPeople, AFewTrainingPeopleBeatTheMeanShapeOnOthers)
{
  AGEX_REQUIRE_SHARED_FILE (agex_test::sharedData ("people2d/ccp/masks/0001.png"), "the CCP photos of ../shared/data/people2d");
  std::vector<agex::LandmarkTrainingImage> train;
  std::vector<CcpPerson> test;
  for (int n = 1; n <= 60; ++n)
  {
    CcpPerson person = ccpPerson (ccpId (n));
    train.push_back ({person.grey, {person.annotation.box}, {person.annotation.landmarks}});
  }
  for (int n = 61; n <= 75; ++n)
    test.push_back (ccpPerson (ccpId (n)));
  agex::ShapePredictorTrainingParams params;
  params.oversampling_amount = 20;
  params.cascade_depth = 8;
  params.num_trees_per_cascade_level = 50;
  params.num_threads = 2;
  params.mirror_map.resize (agex::kContourLandmarkCount);
  for (int i = 0; i < agex::kContourLandmarkCount; ++i)
    params.mirror_map[i] = agex::mirroredContourLandmark (i);
  const agex::ContourShapePredictor predictor = agex::ContourShapePredictor::train (train, params);

  // The mean shape of the training people (and their mirror images), in box coordinates.
  std::vector<cv::Point2f> mean_shape (agex::kContourLandmarkCount, cv::Point2f (0, 0));
  for (const auto &t : train)
    for (int i = 0; i < agex::kContourLandmarkCount; ++i)
    {
      const cv::Rect &box = t.boxes[0];
      const cv::Point2f p = t.shapes[0][i], q = t.shapes[0][agex::mirroredContourLandmark (i)];
      const cv::Point2f normalised ((p.x - box.x) / box.width, (p.y - box.y) / box.height);
      const cv::Point2f mirrored (1.f - (q.x - box.x) / box.width, (q.y - box.y) / box.height);
      mean_shape[i] += (normalised + mirrored) * (0.5f / train.size ());
    }
  double trained = 0, mean = 0, trained_contour = 0, mean_contour = 0;
  for (const CcpPerson &person : test)
  {
    const cv::Rect &box = person.annotation.box;
    const std::vector<cv::Point2f> predicted = predictor.predict (person.grey, box);
    std::vector<cv::Point2f> placed;
    for (const cv::Point2f &m : mean_shape)
      placed.emplace_back (box.x + m.x * box.width, box.y + m.y * box.height);
    trained += meanError (predicted, person.annotation.landmarks) / box.height;
    mean += meanError (placed, person.annotation.landmarks) / box.height;
    trained_contour += agex::meanDistanceToClosedPolyline (predicted, person.annotation.landmarks) / box.height;
    mean_contour += agex::meanDistanceToClosedPolyline (placed, person.annotation.landmarks) / box.height;
  }
  const double n = static_cast<double> (test.size ());
  RecordProperty ("error_per_box_height", cv::format ("trained %.4f, mean shape %.4f", trained / n, mean / n));
  RecordProperty ("contour_per_box_height", cv::format ("trained %.4f, mean shape %.4f", trained_contour / n, mean_contour / n));
  EXPECT_LT (trained, 0.9 * mean) << "per box height: trained " << trained / n << ", mean shape " << mean / n;
  EXPECT_LT (trained_contour, 0.9 * mean_contour)
    << "to the contour, per box height: trained " << trained_contour / n << ", mean shape " << mean_contour / n;
}

// The bundled detector and shape predictor were trained on CCP without these photos.
TEST (CcpPeople, BundledModelsFindAndOutlineHeldOutPeople)
{
  AGEX_REQUIRE_SHARED_FILE (agex_test::sharedData ("people2d/ccp/masks/0900.png"), "the CCP photos of ../shared/data/people2d");
  const agex::PeopleDetector detector =
    agex::PeopleDetector::load (std::string (AGEX_SOURCE_DIR) + "/data/models/agex_people_detector.svm");
  const agex::ContourShapePredictor predictor =
    agex::ContourShapePredictor::load (std::string (AGEX_SOURCE_DIR) + "/data/models/agex_contour_landmarks.dat");
  int found = 0;
  double error = 0;
  for (const std::string &id : kHeldOut)
  {
    const CcpPerson person = ccpPerson (id);
    const cv::Rect truth = agex::uprightBox (person.annotation.tight_box, 0.41);
    double best = 0;
    for (const agex::PersonDetection &d : detector.detect (person.grey))
      best = std::max (best, agex::boxIoU (agex::uprightBox (d.box, 0.41), truth));
    found += best >= 0.5;
    if (id == "0900")
    {
      EXPECT_GE (best, 0.5) << "the person of CCP 0900 is not found";
    }
    error += meanError (predictor.predict (person.grey, person.annotation.box), person.annotation.landmarks) /
             person.annotation.box.height;
  }
  RecordProperty ("held_out_found", found);
  RecordProperty ("held_out_error_per_box_height", cv::format ("%.4f", error / kHeldOut.size ()));
  EXPECT_GE (found, 8) << "of " << kHeldOut.size () << " held-out people";
  EXPECT_LT (error / kHeldOut.size (), 0.06) << "mean landmark error per box height";
}
}  // namespace

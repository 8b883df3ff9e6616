#include <agex/landmarks/people_landmarks.h>

#include <agex/common/statistics.h>
#include <agex/landmarks/contour_annotation.h>

#include <chrono>
#include <stdexcept>

namespace agex
{
ContourShapePredictor
loadContourModel (const std::string &path)
{
  ContourShapePredictor predictor = ContourShapePredictor::load (path);
  if (predictor.landmarkCount () != kContourLandmarkCount)
    throw std::runtime_error (path + ": the model places " + std::to_string (predictor.landmarkCount ()) +
                              " landmarks, not the " + std::to_string (kContourLandmarkCount) +
                              " contour landmarks agex draws and scores (train one with agex_landmarks_train)");
  return predictor;
}

LandmarkedFrame
landmarkPeople (const cv::Mat &image, const PeopleDetector &detector, const ContourShapePredictor &predictor,
                double threshold)
{
  LandmarkedFrame result;
  const cv::Mat grey = toGrey (image);
  auto start = std::chrono::steady_clock::now ();
  const std::vector<PersonDetection> detections = detector.detect (grey, threshold);
  result.detect_ms = msSince (start);
  start = std::chrono::steady_clock::now ();
  for (const PersonDetection &d : detections)
    result.people.push_back ({d.box, d.score, predictor.predict (grey, squareBox (d.box))});
  result.landmarks_ms = msSince (start);
  return result;
}
}  // namespace agex

#pragma once
// People and their 180 contour landmarks in an image: the people detector's boxes, the shape
// predictor run in the square of each box, and how long each stage took (agex_landmarks runs
// this per image or video frame).

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/people_detector.h>

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace agex
{
/** \brief Loads a contour shape predictor and checks that it places the kContourLandmarkCount
  * landmarks (a dlib face model, say, would load but place 68). \throws std::runtime_error */
ContourShapePredictor loadContourModel (const std::string &path);

/** A person found in an image: box, detection score and landmarks. */
struct LandmarkedPerson
{
  cv::Rect box;
  double score = 0.0;
  std::vector<cv::Point2f> landmarks;
};

/** The people of one image or frame and the time each stage took (milliseconds). */
struct LandmarkedFrame
{
  std::vector<LandmarkedPerson> people;
  double detect_ms = 0, landmarks_ms = 0;
};

/** \brief Detects the people of an image (grey, BGR or BGRA) at threshold and places each
  * one's landmarks in the square of its box (squareBox), highest score first. */
LandmarkedFrame landmarkPeople (const cv::Mat &image, const PeopleDetector &detector,
                                const ContourShapePredictor &predictor, double threshold = 0.0);
}  // namespace agex

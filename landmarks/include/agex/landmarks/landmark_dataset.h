#pragma once
// Contour-landmark datasets in memory: an imglab file (agex_annotate writes them) read with
// its images, each box either a person with all 180 landmarks or an ignore region. Training
// (landmark_training.h) and scoring (landmark_evaluation.h) take the images in this form.

#include <opencv2/core.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace agex
{
/** Part names of the shoulders in our imglab files (from COCO keypoints 5 and 6): their
  * distance is the scale of the landmark error per shoulder width. */
extern const char *const kShoulderPartNames[2];

/** A person of an annotated image: square box, 180 contour landmarks, shoulders if known. */
struct AnnotatedPerson
{
  cv::Rect box;        ///< the square box of the XML (the shape predictor's)
  cv::Rect tight_box;  ///< the landmarks' bounding box: the outline's (detection truth)
  std::vector<cv::Point2f> landmarks;
  bool has_shoulders = false;
  cv::Point2f shoulders[2];
};

struct AnnotatedImage
{
  std::string path;
  cv::Mat grey;
  std::vector<AnnotatedPerson> people;
  std::vector<cv::Rect> ignored;  ///< boxes marked ignore or without all landmarks
};

/** \brief Loads an imglab dataset of contour landmarks and its images (grey, readImage).
  * Boxes without any landmark are legal imglab (detector-only annotations) and become ignore
  * regions; they are counted in *boxes_without_landmarks, so that a caller can say so rather
  * than train on a half-annotated dataset without a word.
  * \throws std::runtime_error naming the file and the problem (for a box with some but not
  *         all of the landmarks, its line) */
std::vector<AnnotatedImage> loadLandmarkDataset (const std::string &xml_path,
                                                 std::size_t *boxes_without_landmarks = nullptr);
}  // namespace agex

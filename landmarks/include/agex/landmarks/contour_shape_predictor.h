#pragma once
// Landmark regression inside a box: dlib's cascade of regression trees (Kazemi & Sullivan
// 2014) behind plain OpenCV types, so that users of this header need no dlib.

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

namespace agex
{
/** dlib::shape_predictor_trainer's parameters; the defaults are the seed's choices
  * (oversampling 500, nu 0.05, tree depth 2) and dlib's for the rest. */
struct ShapePredictorTrainingParams
{
  unsigned long oversampling_amount = 500;
  double oversampling_translation_jitter = 0.0;
  double nu = 0.05;
  unsigned long tree_depth = 2;
  unsigned long cascade_depth = 10;
  unsigned long num_trees_per_cascade_level = 500;
  unsigned long feature_pool_size = 400;
  double feature_pool_region_padding = 0.0;
  double lambda = 0.1;
  unsigned long num_test_splits = 20;
  std::string random_seed;
  unsigned long num_threads = 0;  ///< 0: one per core
  bool verbose = false;           ///< dlib's progress on standard output
  /** Landmark i of a left-right mirrored image is mirror_map[i]; when given, mirrored
    * copies of every training image are added. */
  std::vector<int> mirror_map;
};

/** One training image: grey pixels and, per person, a box and its landmarks. */
struct LandmarkTrainingImage
{
  cv::Mat grey;  ///< CV_8UC1
  std::vector<cv::Rect> boxes;
  std::vector<std::vector<cv::Point2f>> shapes;  ///< same landmark count everywhere
};

class ContourShapePredictor
{
public:
  ContourShapePredictor ();
  ~ContourShapePredictor ();
  ContourShapePredictor (ContourShapePredictor &&) noexcept;
  ContourShapePredictor &operator= (ContourShapePredictor &&) noexcept;

  /** \throws std::invalid_argument on no boxes, mismatched sizes or landmark counts */
  static ContourShapePredictor train (const std::vector<LandmarkTrainingImage> &images,
                                      const ShapePredictorTrainingParams &params);
  /** \throws std::runtime_error naming the file when it is missing or not a model */
  static ContourShapePredictor load (const std::string &path);
  /** Writes the model atomically. */
  void save (const std::string &path) const;

  bool empty () const;
  int landmarkCount () const;

  /** Landmarks of the person in box (image pixels). grey: CV_8UC1 (BGR is converted). */
  std::vector<cv::Point2f> predict (const cv::Mat &grey, const cv::Rect &box) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/** A grey copy of an image (BGR, BGRA or grey) for the detector and the predictor. */
cv::Mat toGrey (const cv::Mat &image);
}  // namespace agex

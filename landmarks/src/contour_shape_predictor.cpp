// The only translation unit (with people_detector.cpp) that includes dlib: dlib is heavy
// to compile, so it stays behind the plain-type header.
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/io/atomic_file.h>

#include "dlib_rect.h"

#include <dlib/image_processing/shape_predictor_trainer.h>
#include <dlib/opencv/cv_image.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace agex
{
struct ContourShapePredictor::Impl
{
  dlib::shape_predictor model;
};

ContourShapePredictor::ContourShapePredictor () = default;
ContourShapePredictor::~ContourShapePredictor () = default;
ContourShapePredictor::ContourShapePredictor (ContourShapePredictor &&) noexcept = default;
ContourShapePredictor &ContourShapePredictor::operator= (ContourShapePredictor &&) noexcept = default;

namespace
{
using detail::toDlib;

dlib::full_object_detection
toDetection (const cv::Rect &box, const std::vector<cv::Point2f> &shape)
{
  std::vector<dlib::point> parts;
  parts.reserve (shape.size ());
  for (const cv::Point2f &p : shape)
    parts.emplace_back (std::lround (p.x), std::lround (p.y));
  return dlib::full_object_detection (toDlib (box), parts);
}
}  // namespace

cv::Mat
toGrey (const cv::Mat &image)
{
  if (image.type () == CV_8UC1)
    return image;
  cv::Mat grey;
  if (image.type () == CV_8UC3)
    cv::cvtColor (image, grey, cv::COLOR_BGR2GRAY);
  else if (image.type () == CV_8UC4)
    cv::cvtColor (image, grey, cv::COLOR_BGRA2GRAY);
  else
    throw std::invalid_argument ("toGrey: expected an 8-bit grey, BGR or BGRA image");
  return grey;
}

ContourShapePredictor
ContourShapePredictor::train (const std::vector<LandmarkTrainingImage> &images,
                              const ShapePredictorTrainingParams &params)
{
  // Keep mirrored copies alive: cv_image only wraps them.
  std::vector<cv::Mat> pixels;
  std::vector<std::vector<dlib::full_object_detection>> objects;
  std::size_t landmark_count = 0, people = 0;
  for (const LandmarkTrainingImage &image : images)
  {
    if (image.grey.type () != CV_8UC1)
      throw std::invalid_argument ("shape predictor training: images must be 8-bit grey");
    if (image.boxes.size () != image.shapes.size ())
      throw std::invalid_argument ("shape predictor training: boxes and shapes differ in number");
    for (const auto &shape : image.shapes)
    {
      if (landmark_count == 0)
        landmark_count = shape.size ();
      if (shape.empty () || shape.size () != landmark_count)
        throw std::invalid_argument ("shape predictor training: every shape needs the same, non-zero landmark count");
    }
    if (image.boxes.empty ())
      continue;
    people += image.boxes.size ();
    pixels.push_back (image.grey);
    objects.emplace_back ();
    for (std::size_t b = 0; b < image.boxes.size (); ++b)
      objects.back ().push_back (toDetection (image.boxes[b], image.shapes[b]));
    if (params.mirror_map.empty ())
      continue;
    if (params.mirror_map.size () != landmark_count)
      throw std::invalid_argument ("shape predictor training: the mirror map does not match the landmark count");
    cv::Mat mirrored;
    cv::flip (image.grey, mirrored, 1);
    pixels.push_back (mirrored);
    objects.emplace_back ();
    const int width = image.grey.cols;
    for (std::size_t b = 0; b < image.boxes.size (); ++b)
    {
      const cv::Rect &box = image.boxes[b];
      std::vector<cv::Point2f> shape (landmark_count);
      for (std::size_t i = 0; i < landmark_count; ++i)
      {
        const cv::Point2f p = image.shapes[b][i];
        shape[params.mirror_map[i]] = cv::Point2f (width - 1 - p.x, p.y);
      }
      objects.back ().push_back (toDetection (cv::Rect (width - box.x - box.width, box.y, box.width, box.height), shape));
    }
  }
  if (people == 0)
    throw std::invalid_argument ("shape predictor training: no annotated person");

  std::vector<dlib::cv_image<unsigned char>> views;
  views.reserve (pixels.size ());
  for (const cv::Mat &p : pixels)
    views.emplace_back (p);

  dlib::shape_predictor_trainer trainer;
  trainer.set_oversampling_amount (params.oversampling_amount);
  trainer.set_oversampling_translation_jitter (params.oversampling_translation_jitter);
  trainer.set_nu (params.nu);
  trainer.set_tree_depth (params.tree_depth);
  trainer.set_cascade_depth (params.cascade_depth);
  trainer.set_num_trees_per_cascade_level (params.num_trees_per_cascade_level);
  trainer.set_feature_pool_size (params.feature_pool_size);
  trainer.set_feature_pool_region_padding (params.feature_pool_region_padding);
  trainer.set_lambda (params.lambda);
  trainer.set_num_test_splits (params.num_test_splits);
  trainer.set_random_seed (params.random_seed);
  trainer.set_num_threads (params.num_threads ? params.num_threads : std::max (1u, std::thread::hardware_concurrency ()));
  if (params.verbose)
    trainer.be_verbose ();

  ContourShapePredictor predictor;
  predictor.impl_ = std::make_unique<Impl> ();
  predictor.impl_->model = trainer.train (views, objects);
  return predictor;
}

namespace
{
// dlib trusts a model's indices when it predicts, so a damaged file that still parses
// would read out of bounds. The parts are read as dlib serialises them (version 1) and
// checked against each other before the model itself is deserialised.
std::string
shapePredictorProblem (const std::string &bytes)
{
  std::istringstream in (bytes);
  int version = 0;
  dlib::matrix<float, 0, 1> initial_shape;
  std::vector<std::vector<dlib::impl::regression_tree>> forests;
  std::vector<std::vector<unsigned long>> anchor_idx;
  std::vector<std::vector<dlib::vector<float, 2>>> deltas;
  dlib::deserialize (version, in);
  if (version != 1)
    return "unknown shape predictor version " + std::to_string (version);
  dlib::deserialize (initial_shape, in);
  dlib::deserialize (forests, in);
  dlib::deserialize (anchor_idx, in);
  dlib::deserialize (deltas, in);
  const auto shape_size = static_cast<std::size_t> (initial_shape.size ());
  if (shape_size == 0 || shape_size % 2 != 0)
    return "the mean shape has " + std::to_string (shape_size) + " coordinates";
  for (long i = 0; i < initial_shape.size (); ++i)
    if (!std::isfinite (initial_shape (i)))
      return "the mean shape holds a value that is not finite";
  if (anchor_idx.size () != forests.size () || deltas.size () != forests.size ())
    return "cascade levels, anchors and offsets differ in number";
  for (std::size_t level = 0; level < forests.size (); ++level)
  {
    const std::size_t pixels = anchor_idx[level].size ();
    if (deltas[level].size () != pixels)
      return "level " + std::to_string (level) + ": anchors and offsets differ in number";
    for (const unsigned long anchor : anchor_idx[level])
      if (anchor >= shape_size / 2)
        return "level " + std::to_string (level) + ": a feature pixel is anchored to landmark " +
               std::to_string (anchor) + " of " + std::to_string (shape_size / 2);
    for (const auto &tree : forests[level])
    {
      const std::size_t leaves = tree.leaf_values.size ();
      if (leaves == 0 || (leaves & (leaves - 1)) != 0 || leaves != tree.splits.size () + 1)
        return "level " + std::to_string (level) + ": a tree with " + std::to_string (tree.splits.size ()) +
               " splits and " + std::to_string (leaves) + " leaves";
      for (const auto &split : tree.splits)
        if (split.idx1 >= pixels || split.idx2 >= pixels || !std::isfinite (split.thresh))
          return "level " + std::to_string (level) + ": a split on feature pixel " +
                 std::to_string (std::max (split.idx1, split.idx2)) + " of " + std::to_string (pixels);
      for (const auto &leaf : tree.leaf_values)
        if (static_cast<std::size_t> (leaf.size ()) != shape_size)
          return "level " + std::to_string (level) + ": a leaf with " + std::to_string (leaf.size ()) +
                 " values for a shape of " + std::to_string (shape_size);
    }
  }
  return "";
}
}  // namespace

ContourShapePredictor
ContourShapePredictor::load (const std::string &path)
{
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw std::runtime_error (path + ": cannot open the shape predictor model");
  const std::string bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  ContourShapePredictor predictor;
  predictor.impl_ = std::make_unique<Impl> ();
  std::string problem;
  try
  {
    problem = shapePredictorProblem (bytes);
    if (problem.empty ())
    {
      std::istringstream model (bytes);
      dlib::deserialize (predictor.impl_->model, model);
    }
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error (path + ": not a dlib shape predictor model (" + std::string (e.what ()) + ")");
  }
  if (!problem.empty ())
    throw std::runtime_error (path + ": damaged shape predictor model (" + problem + ")");
  if (predictor.impl_->model.num_parts () == 0)
    throw std::runtime_error (path + ": the shape predictor model has no landmarks");
  return predictor;
}

void
ContourShapePredictor::save (const std::string &path) const
{
  if (empty ())
    throw std::logic_error ("ContourShapePredictor::save: no model");
  std::ostringstream out;
  dlib::serialize (impl_->model, out);
  writeFileAtomic (path, out.str ());
}

bool
ContourShapePredictor::empty () const
{
  return !impl_ || impl_->model.num_parts () == 0;
}

int
ContourShapePredictor::landmarkCount () const
{
  return empty () ? 0 : static_cast<int> (impl_->model.num_parts ());
}

std::vector<cv::Point2f>
ContourShapePredictor::predict (const cv::Mat &image, const cv::Rect &box) const
{
  if (empty ())
    throw std::logic_error ("ContourShapePredictor::predict: no model");
  const cv::Mat grey = toGrey (image);
  const dlib::full_object_detection shape = impl_->model (dlib::cv_image<unsigned char> (grey), toDlib (box));
  std::vector<cv::Point2f> points (shape.num_parts ());
  for (unsigned long i = 0; i < shape.num_parts (); ++i)
    points[i] = cv::Point2f (static_cast<float> (shape.part (i).x ()), static_cast<float> (shape.part (i).y ()));
  return points;
}
}  // namespace agex

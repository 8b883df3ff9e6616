// With contour_shape_predictor.cpp, the only translation unit that includes dlib.
#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/people_detector.h>
#include <agex/common/pixel_box.h>
#include <agex/io/atomic_file.h>

#include "dlib_rect.h"

#include <dlib/image_processing.h>
#include <dlib/image_transforms/image_pyramid.h>
#include <dlib/opencv/cv_image.h>
#include <dlib/svm_threaded.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace agex
{
namespace
{
/** Highest score first; ties by position, so that the order never depends on the search. */
void
sortByScore (std::vector<PersonDetection> &people)
{
  std::sort (people.begin (), people.end (), [] (const PersonDetection &a, const PersonDetection &b) {
    return std::make_tuple (-a.score, a.box.y, a.box.x, a.box.width) <
           std::make_tuple (-b.score, b.box.y, b.box.x, b.box.width);
  });
}

using detail::toDlib;
using detail::toCv;
using Scanner = dlib::scan_fhog_pyramid<dlib::pyramid_down<6>>;
constexpr char kMagic[] = "agex_people_detector_fhog 2";
// Several trained detectors with their offsets (PeopleDetector::combine) in one file.
constexpr char kEnsembleMagic[] = "agex_people_detector_fhog_ensemble 1";
constexpr std::uint32_t kMaxEnsembleMembers = 8;
// A trained 48x96 detector is 35 KB; no file near this is a detector, so nothing larger is
// decoded (dlib allocates what a damaged file claims).
constexpr std::uintmax_t kMaxDetectorFileBytes = std::uintmax_t (64) << 20;
constexpr double kPeopleNmsIoU = 0.5, kPeopleNmsCovered = 0.95;
// OpenCV's people: the person fills the middle 0.75 of its 64x128 window's height.
constexpr double kOpenCvPersonHeight = 0.75, kOpenCvPersonAspect = 0.41;

void
checkTrainingParams (const PeopleDetectorTrainingParams &params)
{
  if (!(params.scale > 0.05 && params.scale <= 4.0))
    throw std::invalid_argument ("people detector training: scale must lie in (0.05, 4]");
  if (params.window_width < 16 || params.window_height < 16 || params.window_width > 1024 || params.window_height > 1024)
    throw std::invalid_argument ("people detector training: the window must be 16 to 1024 pixels wide and high");
  if (!(params.c > 0) || !(params.epsilon > 0) || params.c > 1e6)
    throw std::invalid_argument ("people detector training: C must lie in (0, 1e6] and epsilon be positive");
  if (!(params.loss_per_missed_target > 0 && params.loss_per_missed_target <= 1000))
    throw std::invalid_argument ("people detector training: the loss per missed person must lie in (0, 1000]");
  if (params.upsample < 0 || params.upsample > 4)
    throw std::invalid_argument ("people detector training: upsample must lie in 0..4");
  const double lo = params.train_min_person_windows, hi = params.train_max_person_windows;
  if (!(lo == 0 && hi == 0) && !(lo >= 1.0 && hi >= lo && hi <= 100))
    throw std::invalid_argument ("people detector training: the person heights must be 0, 0 (off) or 1 <= min <= max <= 100 "
                                 "window heights");
}

// The factor a training image is resized by: the detection scale, shrunk further so that the
// tallest person is a given number of window heights tall (spread over the images by the
// golden ratio, so that every run picks the same sizes).
double
trainingScale (const std::vector<cv::Rect> &boxes, std::size_t index, const PeopleDetectorTrainingParams &params)
{
  int tallest = 0;
  for (const cv::Rect &box : boxes)
    tallest = std::max (tallest, box.height);
  if (params.train_max_person_windows <= 0 || tallest <= 0)
    return params.scale;
  const double spread = std::fmod (0.5 + 0.6180339887498949 * static_cast<double> (index), 1.0);
  const double windows = params.train_min_person_windows +
                         (params.train_max_person_windows - params.train_min_person_windows) * spread;
  return params.scale * std::min (1.0, windows * params.window_height / (tallest * params.scale));
}

// Two people the suppression would merge cannot both be found: the smaller becomes an ignore
// region (dlib refuses such a labelling).
std::size_t
moveOverlappingToIgnore (std::vector<dlib::rectangle> &targets, std::vector<dlib::rectangle> &regions,
                         const dlib::test_box_overlap &overlap)
{
  std::sort (targets.begin (), targets.end (),
             [] (const dlib::rectangle &a, const dlib::rectangle &b) { return a.area () > b.area (); });
  std::vector<dlib::rectangle> kept;
  for (const dlib::rectangle &box : targets)
  {
    const bool clash = std::any_of (kept.begin (), kept.end (), [&] (const dlib::rectangle &k) { return overlap (k, box); });
    (clash ? regions : kept).push_back (box);
  }
  const std::size_t moved = targets.size () - kept.size ();
  targets = std::move (kept);
  return moved;
}

}  // namespace

struct PeopleDetector::Impl
{
  bool opencv_default = false;
  int upsample = 0;
  double scale = 1.0;
  dlib::object_detector<Scanner> fhog;
  /** fhog again, scanned with dlib::evaluate_detectors: the detector's own operator () loads
    * the image into its scanner, so one detector could not serve two threads at once. */
  std::vector<dlib::object_detector<Scanner>> scanned_alone;
  void setFhog (dlib::object_detector<Scanner> detector)
  {
    fhog = std::move (detector);
    scanned_alone.assign (1, fhog);
  }
  cv::HOGDescriptor hog;
  std::vector<PeopleDetector> members;  ///< an ensemble (combine ()) when not empty
  std::vector<double> offsets;
  /** Trained members with one scale and upsampling: their HOG pyramid is computed once
    * (dlib::evaluate_detectors), each detector's own suppression kept. */
  struct SharedPyramid
  {
    int upsample = 0;
    double scale = 1.0;
    std::vector<std::size_t> members;                  ///< indices into members
    std::vector<dlib::object_detector<Scanner>> fhog;  ///< copies of their detectors, in that order
  };
  std::vector<SharedPyramid> shared;  ///< groups of two or more; the other members run alone
};

namespace
{
/** The grey image a trained detector scans: resized by scale, doubled upsample times. Empty if
  * it shrinks to nothing. */
void
scanImage (const cv::Mat &grey, double scale, int upsample, dlib::array2d<unsigned char> &out)
{
  out.clear ();
  const cv::Size scaled_size (cvRound (grey.cols * scale), cvRound (grey.rows * scale));
  if (scaled_size.width < 1 || scaled_size.height < 1)
    return;
  cv::Mat resized = grey;
  if (scale != 1.0)
    cv::resize (grey, resized, scaled_size, 0, 0, scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
  dlib::assign_image (out, dlib::cv_image<unsigned char> (resized));
  for (int u = 0; u < upsample; ++u)
    dlib::pyramid_up (out);
}

/** Reads one fhog detector as dlib::serialize wrote it (object_detector version 2: the scanner,
  * the overlap test, the weight vectors), checking every size and setting before dlib acts on
  * it: dlib allocates whatever a damaged file claims, divides by its cell size and reads the
  * weights without checking their length. in must be seekable. */
dlib::object_detector<Scanner>
readFhogDetector (std::istream &in)
{
  int version = 0;
  dlib::deserialize (version, in);
  if (version != 2)
    throw std::runtime_error ("fhog detector version " + std::to_string (version) + " (expected 2)");
  const std::streampos scanner_at = in.tellg ();
  // The scanner: its version, its feature pyramid (empty in a saved detector: an array's
  // capacity and size), cell size, padding and window, as scan_fhog_pyramid serializes them.
  int scanner_version = 0, cell_size = 0;
  unsigned long capacity = 1, size = 1, padding = 0, window_width = 0, window_height = 0;
  dlib::deserialize (scanner_version, in);
  dlib::deserialize (capacity, in);
  dlib::deserialize (size, in);
  dlib::deserialize (cell_size, in);
  dlib::deserialize (padding, in);
  dlib::deserialize (window_width, in);
  dlib::deserialize (window_height, in);
  if (scanner_version != 1 || capacity != 0 || size != 0)
    throw std::runtime_error ("an fhog scanner of another version or holding a feature pyramid");
  if (cell_size < 1 || cell_size > 64 || padding > 64 || window_width < 16 || window_width > 1024 ||
      window_height < 16 || window_height > 1024)
    throw std::runtime_error ("fhog cell size " + std::to_string (cell_size) + ", padding " + std::to_string (padding) +
                              " or window " + std::to_string (window_width) + "x" + std::to_string (window_height) +
                              " out of range (1-64, 0-64, 16-1024)");
  in.seekg (scanner_at);
  Scanner scanner;
  dlib::deserialize (scanner, in);
  if (scanner.get_max_pyramid_levels () < 1 || scanner.get_max_pyramid_levels () > 1000 ||
      scanner.get_min_pyramid_layer_width () < 1 || scanner.get_min_pyramid_layer_width () > 100000 ||
      scanner.get_min_pyramid_layer_height () < 1 || scanner.get_min_pyramid_layer_height () > 100000 ||
      !(scanner.get_nuclear_norm_regularization_strength () >= 0 &&
        std::isfinite (scanner.get_nuclear_norm_regularization_strength ())))
    throw std::runtime_error ("fhog pyramid settings out of range");
  dlib::test_box_overlap overlap;
  dlib::deserialize (overlap, in);
  const auto unit = [] (double v) { return v >= 0.0 && v <= 1.0; };
  if (!unit (overlap.get_iou_thresh ()) || !unit (overlap.get_percent_covered_thresh ()))
    throw std::runtime_error ("overlap thresholds outside [0, 1]");
  unsigned long filters = 0;
  dlib::deserialize (filters, in);
  if (filters != 1)
    throw std::runtime_error (std::to_string (filters) + " filters (a trained people detector has 1)");
  // A column vector: -rows, -columns, then the values; one weight per feature and the threshold.
  const std::streampos weights_at = in.tellg ();
  long rows = 0, columns = 0;
  dlib::deserialize (rows, in);
  dlib::deserialize (columns, in);
  const long expected = scanner.get_num_dimensions () + 1;
  if (std::labs (rows) != expected || std::labs (columns) != 1)
    throw std::runtime_error ("a weight vector of " + std::to_string (std::labs (rows)) + "x" +
                              std::to_string (std::labs (columns)) + " values (expected " + std::to_string (expected) +
                              "x1)");
  in.seekg (weights_at);
  dlib::matrix<double, 0, 1> weights;
  dlib::deserialize (weights, in);
  for (long i = 0; i < weights.size (); ++i)
    if (!std::isfinite (weights (i)))
      throw std::runtime_error ("a weight that is not finite");
  return dlib::object_detector<Scanner> (scanner, overlap, std::vector<dlib::matrix<double, 0, 1>>{weights});
}

/** Whether two detectors scan alike: dlib::evaluate_detectors pads every member's features for
  * the largest window and takes the most extreme pyramid settings, so only members that agree
  * on all of them find there exactly what they find alone. */
bool
sameScan (const Scanner &a, const Scanner &b)
{
  return a.get_cell_size () == b.get_cell_size () && a.get_padding () == b.get_padding () &&
         a.get_detection_window_width () == b.get_detection_window_width () &&
         a.get_detection_window_height () == b.get_detection_window_height () &&
         a.get_max_pyramid_levels () == b.get_max_pyramid_levels () &&
         a.get_min_pyramid_layer_width () == b.get_min_pyramid_layer_width () &&
         a.get_min_pyramid_layer_height () == b.get_min_pyramid_layer_height ();
}

/** A detection's box in the input image's pixels. */
cv::Rect
inputBox (const dlib::rectangle &rect, double scale, int upsample)
{
  const double back = 1.0 / ((1 << upsample) * scale);
  const cv::Rect box = toCv (rect);
  return cv::Rect (static_cast<int> (std::lround (box.x * back)), static_cast<int> (std::lround (box.y * back)),
                   static_cast<int> (std::lround (box.width * back)), static_cast<int> (std::lround (box.height * back)));
}
}  // namespace

PeopleDetector::PeopleDetector () = default;
PeopleDetector::~PeopleDetector () = default;
PeopleDetector::PeopleDetector (PeopleDetector &&) noexcept = default;
PeopleDetector &PeopleDetector::operator= (PeopleDetector &&) noexcept = default;

PeopleDetector
PeopleDetector::train (const std::vector<cv::Mat> &grey_images, const std::vector<std::vector<cv::Rect>> &boxes,
                       const PeopleDetectorTrainingParams &params, std::size_t *ignored)
{
  return train (grey_images, boxes, std::vector<std::vector<cv::Rect>> (boxes.size ()), params, ignored);
}

PeopleDetector
PeopleDetector::train (const std::vector<cv::Mat> &grey_images, const std::vector<std::vector<cv::Rect>> &boxes,
                       const std::vector<std::vector<cv::Rect>> &ignore_regions,
                       const PeopleDetectorTrainingParams &params, std::size_t *ignored)
{
  if (grey_images.size () != boxes.size () || grey_images.empty ())
    throw std::invalid_argument ("people detector training: one box list per image needed");
  if (ignore_regions.size () != boxes.size ())
    throw std::invalid_argument ("people detector training: one ignore-region list per image needed");
  checkTrainingParams (params);
  dlib::array<dlib::array2d<unsigned char>> images (grey_images.size ());
  std::vector<std::vector<dlib::rectangle>> targets (grey_images.size ()), regions (grey_images.size ());
  const double aspect = static_cast<double> (params.window_width) / params.window_height;
  for (std::size_t i = 0; i < grey_images.size (); ++i)
  {
    const double factor = trainingScale (boxes[i], i, params);
    const auto scaled = [&] (const cv::Rect &box) {
      return cv::Rect (cv::Point (static_cast<int> (std::lround (box.x * factor)), static_cast<int> (std::lround (box.y * factor))),
                       cv::Size (static_cast<int> (std::lround (box.width * factor)),
                                 static_cast<int> (std::lround (box.height * factor))));
    };
    cv::Mat grey = toGrey (grey_images[i]);
    // At least one pixel: OpenCV asserts on an empty target size, and a tiny image simply
    // holds no box the window can reach (removed below).
    if (factor != 1.0 && !grey.empty ())
      cv::resize (grey, grey,
                  cv::Size (std::max (1, cvRound (grey.cols * factor)), std::max (1, cvRound (grey.rows * factor))), 0, 0,
                  factor < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    dlib::assign_image (images[i], dlib::cv_image<unsigned char> (grey));
    for (const cv::Rect &box : boxes[i])
      targets[i].push_back (toDlib (uprightBox (scaled (box), aspect)));
    for (const cv::Rect &box : ignore_regions[i])
      regions[i].push_back (toDlib (scaled (box)));
  }
  for (int u = 0; u < params.upsample; ++u)
    dlib::upsample_image_dataset<dlib::pyramid_down<2>> (images, targets, regions);
  if (params.add_flips)
    dlib::add_image_left_right_flips (images, targets, regions);

  Scanner scanner;
  scanner.set_detection_window_size (params.window_width, params.window_height);
  dlib::structural_object_detection_trainer<Scanner> trainer (scanner);
  // dlib would take the overlap of non-maximum suppression from the training boxes; with one
  // person per image that is "any overlap at all", and of two people side by side only one
  // would be found. People overlapping more than this are one detection.
  const dlib::test_box_overlap overlap (kPeopleNmsIoU, kPeopleNmsCovered);
  trainer.set_overlap_tester (overlap);
  std::size_t overlapping = 0;
  for (std::size_t i = 0; i < targets.size (); ++i)
    overlapping += moveOverlappingToIgnore (targets[i], regions[i], overlap);
  trainer.set_num_threads (params.num_threads ? params.num_threads : std::max (1u, std::thread::hardware_concurrency ()));
  trainer.set_c (params.c);
  trainer.set_epsilon (params.epsilon);
  trainer.set_loss_per_missed_target (params.loss_per_missed_target);
  if (params.verbose)
    trainer.be_verbose ();
  // Boxes no window position can reach would make the problem infeasible: drop them.
  const std::vector<std::vector<dlib::rectangle>> removed = dlib::remove_unobtainable_rectangles (trainer, images, targets);
  std::size_t removed_count = 0, kept = 0;
  for (std::size_t i = 0; i < removed.size (); ++i)
  {
    removed_count += removed[i].size ();
    kept += targets[i].size ();
  }
  if (ignored)
    *ignored = removed_count + overlapping;
  if (kept == 0)
    throw std::invalid_argument ("people detector training: no box the " + std::to_string (params.window_width) + "x" +
                                 std::to_string (params.window_height) + " window can match");
  PeopleDetector detector;
  detector.impl_ = std::make_unique<Impl> ();
  detector.impl_->upsample = params.upsample;
  detector.impl_->scale = params.scale;
  std::vector<std::vector<dlib::rectangle>> ignore = removed;
  for (std::size_t i = 0; i < ignore.size (); ++i)
    ignore[i].insert (ignore[i].end (), regions[i].begin (), regions[i].end ());
  detector.impl_->setFhog (trainer.train (images, targets, ignore));
  return detector;
}

PeopleDetector
PeopleDetector::openCvDefault (double scale)
{
  if (!(scale > 0.05 && scale <= 4.0))
    throw std::invalid_argument ("OpenCV people detector: scale must lie in (0.05, 4]");
  PeopleDetector detector;
  detector.impl_ = std::make_unique<Impl> ();
  detector.impl_->opencv_default = true;
  detector.impl_->scale = scale;
  detector.impl_->hog.setSVMDetector (cv::HOGDescriptor::getDefaultPeopleDetector ());
  return detector;
}

PeopleDetector
PeopleDetector::combine (std::vector<PeopleDetector> members, const std::vector<double> &offsets)
{
  if (members.empty () || members.size () != offsets.size () || members.size () > kMaxEnsembleMembers)
    throw std::invalid_argument ("people detector ensemble: one offset per member, 1 to " +
                                 std::to_string (kMaxEnsembleMembers) + " members");
  // A member that is an ensemble itself (a detector file with its own threshold) gives its
  // members, their offsets added: one level, so that any ensemble can be saved.
  std::vector<PeopleDetector> flat;
  std::vector<double> flat_offsets;
  for (std::size_t i = 0; i < members.size (); ++i)
  {
    if (!members[i].impl_)
      throw std::invalid_argument ("people detector ensemble: an empty member");
    if (members[i].impl_->members.empty ())
    {
      flat.push_back (std::move (members[i]));
      flat_offsets.push_back (offsets[i]);
      continue;
    }
    Impl &inner = *members[i].impl_;
    for (std::size_t j = 0; j < inner.members.size (); ++j)
    {
      flat.push_back (std::move (inner.members[j]));
      flat_offsets.push_back (offsets[i] + inner.offsets[j]);
    }
  }
  if (flat.size () > kMaxEnsembleMembers)
    throw std::invalid_argument ("people detector ensemble: " + std::to_string (flat.size ()) + " members in all, at most " +
                                 std::to_string (kMaxEnsembleMembers));
  for (const double offset : flat_offsets)
    if (!(offset >= -5.0 && offset <= 5.0))
      throw std::invalid_argument ("people detector ensemble: offsets (a member's own added) must lie in [-5, 5]");
  PeopleDetector detector;
  detector.impl_ = std::make_unique<Impl> ();
  Impl &impl = *detector.impl_;
  impl.members = std::move (flat);
  impl.offsets = std::move (flat_offsets);
  std::vector<bool> grouped (impl.members.size (), false);
  for (std::size_t i = 0; i < impl.members.size (); ++i)
  {
    const Impl &a = *impl.members[i].impl_;
    if (grouped[i] || a.opencv_default)
      continue;
    Impl::SharedPyramid group;
    group.upsample = a.upsample;
    group.scale = a.scale;
    for (std::size_t j = i; j < impl.members.size (); ++j)
    {
      const Impl &b = *impl.members[j].impl_;
      if (!grouped[j] && !b.opencv_default && b.upsample == a.upsample && b.scale == a.scale &&
          sameScan (a.fhog.get_scanner (), b.fhog.get_scanner ()))
      {
        group.members.push_back (j);
        group.fhog.push_back (b.fhog);
      }
    }
    if (group.members.size () < 2)
      continue;
    for (const std::size_t j : group.members)
      grouped[j] = true;
    impl.shared.push_back (std::move (group));
  }
  return detector;
}

PeopleDetector
PeopleDetector::load (const std::string &path)
{
  std::error_code error;
  if (!std::filesystem::is_regular_file (path, error))
    throw std::runtime_error (path + (std::filesystem::exists (path, error) ? ": not a regular file"
                                                                            : ": cannot open the people detector"));
  const std::uintmax_t bytes = std::filesystem::file_size (path, error);
  if (error || bytes > kMaxDetectorFileBytes)
    throw std::runtime_error (path + ": " + std::to_string (bytes) + " bytes, more than a people detector's " +
                              std::to_string (kMaxDetectorFileBytes));
  std::ifstream file (path, std::ios::binary);
  std::string content (static_cast<std::size_t> (bytes), '\0');
  if (!file || !file.read (content.data (), static_cast<std::streamsize> (bytes)))
    throw std::runtime_error (path + ": cannot read the people detector");
  std::istringstream in (content);  // seekable: the decoder looks at sizes before dlib reads them
  const auto readTrained = [] (std::istream &in, Impl &impl) {
    int upsample = 0;
    double scale = 1.0;
    dlib::deserialize (upsample, in);
    dlib::deserialize (scale, in);
    if (upsample < 0 || upsample > 4 || !(scale > 0.05 && scale <= 4.0))
      throw std::runtime_error ("upsample " + std::to_string (upsample) + " or scale " + std::to_string (scale) +
                                " out of range (0-4, (0.05, 4])");
    impl.setFhog (readFhogDetector (in));
    impl.upsample = upsample;
    impl.scale = scale;
  };
  const std::size_t line_end = content.find ('\n');
  const std::string magic = content.substr (0, std::min (line_end, std::size_t (64)));
  if (line_end == std::string::npos || (magic != kMagic && magic != kEnsembleMagic))
    throw std::runtime_error (path + ": not an agex people detector (expected the header '" + std::string (kMagic) +
                              "' or '" + kEnsembleMagic + "')");
  in.seekg (static_cast<std::streamoff> (line_end + 1));
  try
  {
    PeopleDetector detector;
    if (magic == kMagic)
    {
      detector.impl_ = std::make_unique<Impl> ();
      readTrained (in, *detector.impl_);
    }
    else
    {
      std::uint32_t count = 0;
      dlib::deserialize (count, in);
      if (count < 1 || count > kMaxEnsembleMembers)
        throw std::runtime_error ("an ensemble of " + std::to_string (count) + " members (1 to " +
                                  std::to_string (kMaxEnsembleMembers) + ")");
      std::vector<PeopleDetector> members (count);
      std::vector<double> offsets (count, 0.0);
      for (std::uint32_t i = 0; i < count; ++i)
      {
        dlib::deserialize (offsets[i], in);
        if (!(offsets[i] >= -5.0 && offsets[i] <= 5.0))
          throw std::runtime_error ("member " + std::to_string (i) + "'s offset " + std::to_string (offsets[i]) +
                                    " outside [-5, 5]");
        members[i].impl_ = std::make_unique<Impl> ();
        readTrained (in, *members[i].impl_);
      }
      detector = combine (std::move (members), offsets);
    }
    if (in.peek () != std::char_traits<char>::eof ())
      throw std::runtime_error ("bytes after the last detector");
    return detector;
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error (path + ": damaged people detector (" + std::string (e.what ()) + ")");
  }
}

void
PeopleDetector::save (const std::string &path) const
{
  if (!impl_ || impl_->opencv_default)
    throw std::logic_error ("PeopleDetector::save: only trained detectors and their ensembles can be saved (not OpenCV's)");
  const auto writeTrained = [] (const Impl &impl, std::ostream &out) {
    dlib::serialize (impl.upsample, out);
    dlib::serialize (impl.scale, out);
    dlib::serialize (impl.fhog, out);
  };
  std::ostringstream out;
  if (impl_->members.empty ())
  {
    out << kMagic << "\n";
    writeTrained (*impl_, out);
  }
  else
  {
    for (const PeopleDetector &member : impl_->members)
      if (!member.impl_ || member.impl_->opencv_default)
        throw std::logic_error ("PeopleDetector::save: an ensemble's members must be trained detectors (not OpenCV's)");
    out << kEnsembleMagic << "\n";
    dlib::serialize (static_cast<std::uint32_t> (impl_->members.size ()), out);
    for (std::size_t i = 0; i < impl_->members.size (); ++i)
    {
      dlib::serialize (impl_->offsets[i], out);
      writeTrained (*impl_->members[i].impl_, out);
    }
  }
  writeFileAtomic (path, out.str ());
}

bool
PeopleDetector::isOpenCvDefault () const
{
  return impl_ && impl_->opencv_default;
}

std::string
PeopleDetector::description () const
{
  if (!impl_)
    return "none";
  if (!impl_->members.empty ())
  {
    std::string text = "ensemble of " + std::to_string (impl_->members.size ()) + ":";
    for (std::size_t i = 0; i < impl_->members.size (); ++i)
      text += (i ? "; " : " ") + impl_->members[i].description () + ", offset " + std::to_string (impl_->offsets[i]);
    return text;
  }
  if (impl_->opencv_default)
    return "OpenCV HOG people detector (Dalal-Triggs, 64x128)" +
           (impl_->scale != 1.0 ? ", scale " + std::to_string (impl_->scale) : std::string ());
  const Scanner &scanner = impl_->fhog.get_scanner ();
  return "fhog detector, window " + std::to_string (scanner.get_detection_window_width ()) + "x" +
         std::to_string (scanner.get_detection_window_height ()) + ", upsample " + std::to_string (impl_->upsample) +
         ", scale " + std::to_string (impl_->scale);
}

std::vector<PersonDetection>
PeopleDetector::detect (const cv::Mat &image, double threshold) const
{
  if (!impl_)
    throw std::logic_error ("PeopleDetector::detect: no detector");
  std::vector<PersonDetection> people;
  if (image.empty ())
    return people;
  if (!impl_->members.empty ())
  {
    std::vector<PersonDetection> all;
    std::vector<bool> done (impl_->members.size (), false);
    if (!impl_->shared.empty ())
    {
      const cv::Mat grey = toGrey (image);
      dlib::array2d<unsigned char> scanned;
      std::vector<dlib::rect_detection> found;
      for (const Impl::SharedPyramid &group : impl_->shared)
      {
        // One pass at the lowest member threshold; each member then keeps its own. The
        // suppression is per detector, so what a member keeps is what it finds alone.
        double lowest = std::numeric_limits<double>::infinity ();
        for (const std::size_t i : group.members)
        {
          lowest = std::min (lowest, threshold + impl_->offsets[i]);
          done[i] = true;
        }
        scanImage (grey, group.scale, group.upsample, scanned);
        if (scanned.size () == 0)
          continue;
        dlib::evaluate_detectors (group.fhog, scanned, found, lowest);
        for (const dlib::rect_detection &d : found)
        {
          const std::size_t i = group.members[d.weight_index];
          if (d.detection_confidence >= threshold + impl_->offsets[i])
            all.push_back ({inputBox (d.rect, group.scale, group.upsample), d.detection_confidence - impl_->offsets[i]});
        }
      }
    }
    for (std::size_t i = 0; i < impl_->members.size (); ++i)
      if (!done[i])
        for (PersonDetection d : impl_->members[i].detect (image, threshold + impl_->offsets[i]))
        {
          d.score -= impl_->offsets[i];
          all.push_back (d);
        }
    sortByScore (all);
    // The members' own suppression, across members: best first, a box that overlaps a kept
    // one (IoU 0.5, or 95% of the smaller inside the other) is the same person.
    const dlib::test_box_overlap overlap (kPeopleNmsIoU, kPeopleNmsCovered);
    for (const PersonDetection &d : all)
    {
      const bool same = std::any_of (people.begin (), people.end (),
                                     [&] (const PersonDetection &k) { return overlap (toDlib (k.box), toDlib (d.box)); });
      if (!same)
        people.push_back (d);
    }
    return people;
  }
  const cv::Mat grey = toGrey (image);
  if (impl_->opencv_default)
  {
    cv::Mat resized = grey;
    // An image that shrinks to nothing holds no person the detector could see.
    const cv::Size scaled_size (cvRound (grey.cols * impl_->scale), cvRound (grey.rows * impl_->scale));
    if (scaled_size.width < 1 || scaled_size.height < 1)
      return people;
    if (impl_->scale != 1.0)
      cv::resize (grey, resized, scaled_size, 0, 0, impl_->scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    // HOGDescriptor::detectMultiScale's pyramid (steps of 1.05, then groups of at least 3
    // windows), run level by level here: OpenCV 4.6 scans the levels in parallel and appends
    // boxes and scores under separate locks, so a score could end up paired with another
    // level's box, and the order changed from run to run.
    std::vector<cv::Rect> found;
    std::vector<double> weights;
    const cv::HOGDescriptor &hog = impl_->hog;
    double level = 1.0;
    for (int n = 0; n < hog.nlevels; ++n, level *= 1.05)
    {
      const cv::Size size (cvRound (resized.cols / level), cvRound (resized.rows / level));
      if (size.width < hog.winSize.width || size.height < hog.winSize.height)
        break;
      cv::Mat scaled = resized;
      if (n > 0)
        cv::resize (resized, scaled, size, 0, 0, cv::INTER_LINEAR);
      std::vector<cv::Point> hits;
      std::vector<double> hit_scores;
      hog.detect (scaled, hits, hit_scores, threshold, cv::Size (8, 8), cv::Size (0, 0));
      for (std::size_t i = 0; i < hits.size () && i < hit_scores.size (); ++i)
      {
        found.emplace_back (cvRound (hits[i].x * level), cvRound (hits[i].y * level),
                            cvRound (hog.winSize.width * level), cvRound (hog.winSize.height * level));
        weights.push_back (hit_scores[i]);
      }
    }
    hog.groupRectangles (found, weights, 2, 0.2);
    for (std::size_t i = 0; i < found.size (); ++i)
    {
      // The 64x128 window holds a person about 96 pixels tall in its middle.
      const cv::Rect &r = found[i];
      const double side = kOpenCvPersonHeight * r.height / impl_->scale;
      const double cx = (r.x + 0.5 * r.width) / impl_->scale, cy = (r.y + 0.5 * r.height) / impl_->scale;
      const cv::Rect square (static_cast<int> (std::lround (cx - side / 2)), static_cast<int> (std::lround (cy - side / 2)),
                             static_cast<int> (std::lround (side)), static_cast<int> (std::lround (side)));
      people.push_back ({uprightBox (square, kOpenCvPersonAspect), i < weights.size () ? weights[i] : 0.0});
    }
    sortByScore (people);
    return people;
  }
  dlib::array2d<unsigned char> scanned;
  scanImage (grey, impl_->scale, impl_->upsample, scanned);
  if (scanned.size () == 0)
    return people;
  std::vector<dlib::rect_detection> detections;
  dlib::evaluate_detectors (impl_->scanned_alone, scanned, detections, threshold);
  for (const dlib::rect_detection &d : detections)
    people.push_back ({inputBox (d.rect, impl_->scale, impl_->upsample), d.detection_confidence});
  sortByScore (people);
  return people;
}

cv::Rect
uprightBox (const cv::Rect &box, double aspect)
{
  const int width = std::max (1, static_cast<int> (std::lround (aspect * box.height)));
  return cv::Rect (box.x + (box.width - width) / 2, box.y, width, box.height);
}

double
boxIoU (const cv::Rect &a, const cv::Rect &b)
{
  auto box = [] (const cv::Rect &r) {
    return PixelBox{static_cast<float> (r.x), static_cast<float> (r.y), static_cast<float> (r.x + r.width),
                    static_cast<float> (r.y + r.height)};
  };
  return intersectionOverUnion (box (a), box (b));
}
}  // namespace agex

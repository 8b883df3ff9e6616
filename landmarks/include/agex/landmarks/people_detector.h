#pragma once
// People boxes in an image: HOG features and a linear SVM over a sliding window, trained
// with dlib's structural_object_detection_trainer on scan_fhog_pyramid; without a trained
// model, OpenCV's pretrained Dalal-Triggs people detector. Plain OpenCV types only.

#include <opencv2/core.hpp>

#include <memory>
#include <string>
#include <vector>

namespace agex
{
/** Training parameters; epsilon and the flips are the seed's choices. */
struct PeopleDetectorTrainingParams
{
  /** The structural SVM's C. dlib averages the loss over the images, so C does not grow with
    * the data: the seed's 0.65 underfits (see doc/landmarks.md for the comparison). */
  double c = 20.0;
  double epsilon = 0.01;
  /** The loss of a missed person relative to a false detection's (dlib's
    * loss_per_missed_target). Images without people (people-free bands) and the hard negatives
    * mined in each image outweigh the people as their number grows, and the SVM then scores
    * every window below 0; raising this weights the people back. Bounded to (0, 1000]. */
  double loss_per_missed_target = 1.0;
  /** The detection window (pixels): its height is the smallest person found without
    * upsampling, its shape the boxes' (48x96: half as wide as high, which an upright person
    * fits, arms and stride included). Training boxes are made this shape around their centre,
    * keeping their height. */
  int window_width = 48;
  int window_height = 96;
  int upsample = 0;        ///< times the training images (and detection) are doubled
  /** Images are resized by this factor before training and detection: below 1 trades
    * the smallest people found for speed. */
  double scale = 1.0;
  /** Training images are shrunk (never enlarged) so that their tallest person is between
    * these multiples of the window height (spread evenly over the images): the SVM then
    * scans a few small pyramid levels per image instead of a full-size pyramid (an 800-pixel
    * person in a full-size pyramid: 12 levels), and the backgrounds are seen at several
    * scales. 0, 0: images as they are. */
  double train_min_person_windows = 1.2;
  double train_max_person_windows = 3.0;
  bool add_flips = true;   ///< add left-right mirrored training images
  unsigned long num_threads = 0;  ///< 0: one per core
  bool verbose = false;
};

struct PersonDetection
{
  /** The person's box: the detection window's shape (upright, the person's height, centred);
    * squareBox (box) is the box the contour shape predictor takes. */
  cv::Rect box;
  double score = 0.0;
};

/** box made aspect wide per height around its centre, its height kept. */
cv::Rect uprightBox (const cv::Rect &box, double aspect);

class PeopleDetector
{
public:
  PeopleDetector ();
  ~PeopleDetector ();
  PeopleDetector (PeopleDetector &&) noexcept;
  PeopleDetector &operator= (PeopleDetector &&) noexcept;

  /** Trains on grey images with their people boxes; boxes the window cannot match
    * (too small, wrong shape, overlapping) are ignored and counted in *ignored.
    * \throws std::invalid_argument when nothing is left to train on */
  static PeopleDetector train (const std::vector<cv::Mat> &grey_images, const std::vector<std::vector<cv::Rect>> &boxes,
                               const PeopleDetectorTrainingParams &params, std::size_t *ignored = nullptr);
  /** As above, with regions per image (imglab's ignore boxes) that count neither as a person
    * nor as background: windows there are never used as negatives. */
  static PeopleDetector train (const std::vector<cv::Mat> &grey_images, const std::vector<std::vector<cv::Rect>> &boxes,
                               const std::vector<std::vector<cv::Rect>> &ignore_regions,
                               const PeopleDetectorTrainingParams &params, std::size_t *ignored = nullptr);
  /** OpenCV's pretrained people detector (64x128 window, INRIA people; the person is the
    * middle 0.75 of the window's height, boxes 0.42 wide per height). Images are
    * resized by \p scale before detection: below 1 it is faster (about scale^2 of the
    * time) and misses people shorter than about 96 / scale pixels (the apps use 0.5).
    * \throws std::invalid_argument unless 0.05 < scale <= 4 */
  static PeopleDetector openCvDefault (double scale = 1.0);
  /** Several detectors as one: each member's detections at its own threshold (offsets[i] added
    * to detect ()'s), their scores shifted by -offsets[i] so that every member's threshold is
    * 0, merged and suppressed as one detector's. Detectors trained on different photos (CCP's
    * fashion photos, INRIA's street crops) find different people; scores of different SVMs are
    * only roughly comparable, hence the offsets. One member with an offset is a detector with
    * its own operating threshold. A member that is an ensemble gives its members, their
    * offsets added (ensembles are one level deep). save () writes an ensemble of trained
    * members as one file.
    * \throws std::invalid_argument for no member or more than 8 in all, an empty one, a count
    * mismatch or an offset outside [-5, 5] (a member's own added) */
  static PeopleDetector combine (std::vector<PeopleDetector> members, const std::vector<double> &offsets);
  /** A trained detector or an ensemble of them (save ()); at most 8 members, offsets in
    * [-5, 5], regular files up to 64 MB. Every size and setting dlib would act on (the
    * scanner's, the weights' count) is checked before dlib reads it.
    * \throws std::runtime_error naming the file when it is missing, not a detector or damaged */
  static PeopleDetector load (const std::string &path);
  /** Writes the trained detector, or the ensemble of trained detectors with their offsets,
    * atomically. \throws std::logic_error for OpenCV's detector or an ensemble holding it */
  void save (const std::string &path) const;

  bool isOpenCvDefault () const;
  std::string description () const;

  /** People in an image (grey or BGR), highest score first; threshold shifts the SVM's
    * decision value. Safe to call from several threads at once on one detector. The search covers every scale from the window's height up to the image's
    * (a pyramid of steps of 5/6), so people of 96 to 960 pixels in a 1280x960 image. */
  std::vector<PersonDetection> detect (const cv::Mat &image, double threshold = 0.0) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/** Intersection over union of two boxes. */
double boxIoU (const cv::Rect &a, const cv::Rect &b);
}  // namespace agex

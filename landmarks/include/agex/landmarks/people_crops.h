#pragma once
// Person crops (pedestrian datasets such as INRIA's: one upright person per small image, at a
// known box) and people-free backgrounds, for training and scoring the people detector. A crop
// holds too little background to teach the detector what a person is not (its margins are
// narrower than the detection window), so crops are pasted into larger photos whose own people
// are ignore regions; and photos with their people cut away give backgrounds where every
// window is a negative.

#include <agex/landmarks/landmark_dataset.h>
#include <agex/landmarks/pasted_people.h>

#include <opencv2/core.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace agex
{
/** Crops of one layout: the person is the same box in every crop. */
struct PeopleCrops
{
  std::vector<cv::Mat> images;  ///< CV_8UC1, all the same size
  std::vector<std::string> names;
  /** The person's box in each crop (INRIA's 96x160 crops: 24,32 48x96, the middle 0.75 of
    * the 64x128 window at 16,16). */
  cv::Rect person;
};

/** \brief Reads every .png / .jpg / .jpeg in folder (sorted by name) as grey images.
  * \throws std::runtime_error naming the folder or the file: no images, an unreadable one, crops
  * of different sizes, or a person box not inside the crop */
PeopleCrops readPeopleCrops (const std::string &folder, const cv::Rect &person);

/** The indices 0..count-1 of fold (i mod folds == fold: test = true) or of the other folds;
  * fold -1: all of them (test = false) or none (test = true).
  * \throws std::invalid_argument unless 2 <= folds <= 100 and -1 <= fold < folds */
std::vector<std::size_t> foldIndices (std::size_t count, int folds, int fold, bool test);

/** The source photo of each crop, numbered 0, 1, ... in the order of the names: crops cut from
  * one photo share their name but a final letter (INRIA's crop001001a, crop001001c: the same
  * background, often the same people), so that no photo is in two folds. A name without such a
  * letter is its own photo. */
std::vector<std::size_t> cropSourcePhotos (const std::vector<std::string> &names);

/** As foldIndices, by group: index i is in fold groups[i] mod folds. */
std::vector<std::size_t> foldIndices (const std::vector<std::size_t> &groups, int folds, int fold, bool test);

struct PastedCropsParams
{
  /** Each background is resized so that its height is between these (pixels; spread evenly
    * over the images by the golden ratio, never enlarged), then the crops' people are pasted
    * with box heights between min_height and max_height pixels (spread likewise; smaller
    * where the crop would not fit). */
  int min_background_height = 240;
  int max_background_height = 480;
  int min_height = 96;
  int max_height = 192;
  /** Feet between this fraction of the height and the bottom. */
  double min_feet = 0.45;
  int people_per_image = 2;
};

/** \brief Pastes crops[which] (each in turn, wrapping round) people_per_image to a background:
  * the whole crop, its margin faded into the background so that no rectangle edge is left.
  * The pasted people's boxes are the boxes to find; the backgrounds' people and ignore boxes
  * are ignore regions. Deterministic.
  * \throws std::invalid_argument on parameters out of range (heights 16 to 2000 pixels, min <=
  * max; 1 to 10 people per image) */
PeopleImages pasteCrops (const std::vector<AnnotatedImage> &backgrounds, const std::vector<std::size_t> &background_which,
                         const PeopleCrops &crops, const std::vector<std::size_t> &which,
                         const PastedCropsParams &params = PastedCropsParams ());

struct PeopleFreeParams
{
  /** Every person's outline (and ignore box) is grown by this fraction of its height before
    * the regions clear of it are cut out. */
  double dilation = 0.1;
  /** Regions narrower or lower than this fraction of the image's height are dropped. */
  double min_width = 0.12;
  double min_height = 0.25;
  /** The regions are resized so that their height is between these (pixels, spread by the
    * golden ratio): backgrounds at the scales the detector sees people at. */
  int min_region_height = 200;
  int max_region_height = 480;
};

/** \brief The bands of an image (full-height column bands, full-width row bands) that touch
  * no person's outline and no ignore box, each grown by params.dilation of its height. The
  * rectangles are in the image's pixels. \throws std::invalid_argument on parameters out of
  * range */
std::vector<cv::Rect> peopleFreeRegions (const AnnotatedImage &image, const PeopleFreeParams &params = PeopleFreeParams ());

/** \brief Every people-free region of images[which], cut out and resized (params): images with
  * no person to find, where every window is a negative. */
PeopleImages peopleFreeImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                               const PeopleFreeParams &params = PeopleFreeParams ());
}  // namespace agex

#pragma once
// People pasted into other photos, for training and scoring the people detector. A dataset
// whose photos each show one person filling the frame (as Clothing Co-Parsing's do) teaches a
// sliding-window detector that a person is whatever fills the frame: trained on the photos
// themselves, the fhog detector fired on windows as large as the image in any photo. Cut out
// along their outlines and pasted, smaller, into another photo's scene, the same people stand
// among real backgrounds at many sizes, several to an image.

#include <opencv2/core.hpp>

#include <vector>

namespace agex
{
struct PastedPeopleParams
{
  /** The pasted people's heights, as fractions of the background image's height, spread evenly
    * over the images (by the golden ratio, so every run makes the same images) between these;
    * the people of one image are within 15% of each other. */
  double min_height = 0.15;
  double max_height = 0.6;
  /** Feet between this fraction of the height and the bottom (people stand on the ground). */
  double min_feet = 0.55;
  /** The cut-out's edge is blended over this many pixels (at the pasted size). */
  double feather_px = 1.5;
  /** People pasted into each background (each from another image). */
  int people_per_image = 2;
};

/** Images with their people (boxes to find) and ignore regions. */
struct PeopleImages
{
  std::vector<cv::Mat> images;  ///< CV_8UC1
  std::vector<std::vector<cv::Rect>> boxes;
  std::vector<std::vector<cv::Rect>> ignore;
};

/** \brief Pastes people into each other's photos: image i becomes the background of
  * people_per_image people of other images (i + 1, i + 2, ... wrapping round), each cut out
  * along its outline (a closed polygon in its image's pixels, e.g. its 180 contour landmarks),
  * scaled to its height and put where it overlaps the background's people and the other pasted
  * people least. The pasted people are the boxes to find (their outlines' boxes); the
  * background's own people, which may be partly covered, and its ignore regions are ignore
  * regions. Deterministic.
  * \throws std::invalid_argument on sizes that do not match or parameters out of range */
PeopleImages pastePeople (const std::vector<cv::Mat> &grey_images,
                          const std::vector<std::vector<std::vector<cv::Point2f>>> &outlines,
                          const std::vector<std::vector<cv::Rect>> &ignore_regions,
                          const PastedPeopleParams &params = PastedPeopleParams ());
}  // namespace agex

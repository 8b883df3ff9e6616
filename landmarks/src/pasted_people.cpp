#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/pasted_people.h>
#include <agex/landmarks/people_detector.h>

#include "placement.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>

namespace agex
{
namespace
{
void
checkParams (const PastedPeopleParams &p)
{
  if (!(p.min_height > 0 && p.min_height <= p.max_height && p.max_height <= 1))
    throw std::invalid_argument ("pasted people: heights must satisfy 0 < min <= max <= 1 (of the image's height)");
  if (!(p.min_feet >= 0 && p.min_feet <= 1) || !(p.feather_px >= 0 && p.feather_px <= 20))
    throw std::invalid_argument ("pasted people: min_feet must lie in [0, 1], feather_px in [0, 20]");
  if (p.people_per_image < 1 || p.people_per_image > 10)
    throw std::invalid_argument ("pasted people: 1 to 10 people per image");
}

// Blends the person inside outline (in source's pixels) into canvas so that its outline's box
// lands on target.
void
pasteOne (const cv::Mat &source, const std::vector<cv::Point2f> &outline, const cv::Rect &target, double feather_px,
          cv::Mat &canvas)
{
  const cv::Rect tight = cv::boundingRect (outline);
  const double k = static_cast<double> (target.height) / std::max (1, tight.height);
  const int margin = static_cast<int> (std::ceil ((2.0 * feather_px + 2.0) / k));
  const cv::Rect crop = cv::Rect (tight.x - margin, tight.y - margin, tight.width + 2 * margin, tight.height + 2 * margin) &
                        cv::Rect (0, 0, source.cols, source.rows);
  if (crop.area () <= 0)
    return;
  cv::Mat mask = cv::Mat::zeros (crop.size (), CV_8UC1);
  std::vector<cv::Point> polygon;
  for (const cv::Point2f &p : outline)
    polygon.emplace_back (static_cast<int> (std::lround (p.x)) - crop.x, static_cast<int> (std::lround (p.y)) - crop.y);
  cv::fillPoly (mask, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar (255));
  const cv::Size scaled (std::max (1, static_cast<int> (std::lround (crop.width * k))),
                         std::max (1, static_cast<int> (std::lround (crop.height * k))));
  const int interpolation = k < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR;
  cv::Mat person, alpha;
  cv::resize (source (crop), person, scaled, 0, 0, interpolation);
  cv::resize (mask, alpha, scaled, 0, 0, interpolation);
  alpha.convertTo (alpha, CV_32F, 1.0 / 255);
  if (feather_px > 0)
    cv::GaussianBlur (alpha, alpha, cv::Size (0, 0), feather_px);
  // Where the crop's corner lands so that the tight box lands on target.
  const cv::Point corner (target.x - static_cast<int> (std::lround ((tight.x - crop.x) * k)),
                          target.y - static_cast<int> (std::lround ((tight.y - crop.y) * k)));
  const cv::Rect destination = cv::Rect (corner, scaled) & cv::Rect (0, 0, canvas.cols, canvas.rows);
  for (int y = destination.y; y < destination.br ().y; ++y)
    for (int x = destination.x; x < destination.br ().x; ++x)
    {
      const float a = alpha.at<float> (y - corner.y, x - corner.x);
      unsigned char &out = canvas.at<unsigned char> (y, x);
      out = cv::saturate_cast<unsigned char> (a * person.at<unsigned char> (y - corner.y, x - corner.x) + (1.f - a) * out);
    }
}
}  // namespace

PeopleImages
pastePeople (const std::vector<cv::Mat> &grey_images, const std::vector<std::vector<std::vector<cv::Point2f>>> &outlines,
             const std::vector<std::vector<cv::Rect>> &ignore_regions, const PastedPeopleParams &params)
{
  checkParams (params);
  if (outlines.size () != grey_images.size () || ignore_regions.size () != grey_images.size ())
    throw std::invalid_argument ("pasted people: one outline list and one ignore list per image needed");
  std::vector<std::pair<std::size_t, std::size_t>> people;  // (image, person)
  for (std::size_t i = 0; i < outlines.size (); ++i)
    for (std::size_t k = 0; k < outlines[i].size (); ++k)
      if (outlines[i][k].size () >= 3 && cv::boundingRect (outlines[i][k]).height > 0)
        people.emplace_back (i, k);
  PeopleImages result;
  std::size_t next = 0;
  for (std::size_t i = 0; i < grey_images.size (); ++i)
  {
    cv::Mat canvas = toGrey (grey_images[i]).clone ();
    std::vector<cv::Rect> ignore = ignore_regions[i], boxes;
    for (const auto &outline : outlines[i])
      if (!outline.empty ())
        ignore.push_back (cv::boundingRect (outline));
    std::vector<cv::Rect> taken = ignore;
    for (int p = 0; p < params.people_per_image && !people.empty () && !canvas.empty (); ++p)
    {
      // The next person in turn that is not from this image.
      std::size_t tries = 0;
      while (people[next % people.size ()].first == i && tries++ < people.size ())
        ++next;
      const auto [source, person] = people[next++ % people.size ()];
      if (source == i)
        break;
      const std::vector<cv::Point2f> &outline = outlines[source][person];
      const cv::Rect tight = cv::boundingRect (outline);
      // One height per image, each person within 15% of it: the trainer shrinks each image by its
      // tallest person, and a much smaller one would then be too small for the window.
      const double spread = detail::goldenSpread (i);
      const double vary = 1.0 + 0.3 * (std::fmod (0.5 + 0.7548776662466927 * static_cast<double> (p), 1.0) - 0.5);
      double height = canvas.rows * std::clamp ((params.min_height + (params.max_height - params.min_height) * spread) * vary,
                                                params.min_height, params.max_height);
      height = std::min (height, static_cast<double> (canvas.cols - 1) * tight.height / std::max (1, tight.width));
      const cv::Size size (std::max (1, static_cast<int> (std::lround (height * tight.width / tight.height))),
                           std::max (1, static_cast<int> (std::lround (height))));
      if (size.width >= canvas.cols || size.height >= canvas.rows)
        continue;
      std::mt19937 rng (static_cast<unsigned> (i * 31 + p));
      std::uniform_int_distribution<int> x_of (0, canvas.cols - size.width);
      const int lowest_feet = std::max (size.height, static_cast<int> (std::lround (params.min_feet * canvas.rows)));
      std::uniform_int_distribution<int> feet_of (std::min (lowest_feet, canvas.rows), canvas.rows);
      const cv::Rect best = detail::leastCollidingPlace (
          [&] {
            const cv::Rect box (x_of (rng), feet_of (rng) - size.height, size.width, size.height);
            return std::make_pair (box, box);
          },
          taken);
      pasteOne (toGrey (grey_images[source]), outline, best, params.feather_px, canvas);
      boxes.push_back (best);
      taken.push_back (best);
    }
    result.images.push_back (canvas);
    result.boxes.push_back (boxes);
    result.ignore.push_back (ignore);
  }
  return result;
}
}  // namespace agex

#include <agex/landmarks/people_crops.h>

#include <agex/landmarks/contour_shape_predictor.h>
#include <agex/landmarks/image_files.h>

#include "placement.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

namespace agex
{
namespace
{
cv::Rect
scaledRect (const cv::Rect &r, double k)
{
  return cv::Rect (static_cast<int> (std::lround (r.x * k)), static_cast<int> (std::lround (r.y * k)),
                   static_cast<int> (std::lround (r.width * k)), static_cast<int> (std::lround (r.height * k)));
}

// Marks the columns (or rows) that lie within grow pixels of a set pixel of mask.
void
markGrown (const cv::Mat &mask, int grow, bool columns, std::vector<bool> &taken)
{
  cv::Mat profile;
  cv::reduce (mask, profile, columns ? 0 : 1, cv::REDUCE_MAX);
  const int n = static_cast<int> (taken.size ());
  for (int i = 0; i < n; ++i)
    if ((columns ? profile.at<unsigned char> (0, i) : profile.at<unsigned char> (i, 0)) > 0)
      for (int j = std::max (0, i - grow); j <= std::min (n - 1, i + grow); ++j)
        taken[j] = true;
}
}  // namespace

PeopleCrops
readPeopleCrops (const std::string &folder, const cv::Rect &person)
{
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory (folder, error))
    throw std::runtime_error (folder + ": not a folder of person crops");
  std::vector<fs::path> files;
  for (const auto &entry : fs::directory_iterator (folder))
  {
    std::string ext = entry.path ().extension ().string ();
    std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return static_cast<char> (std::tolower (c)); });
    if (entry.is_regular_file () && (ext == ".png" || ext == ".jpg" || ext == ".jpeg"))
      files.push_back (entry.path ());
  }
  std::sort (files.begin (), files.end ());
  if (files.empty ())
    throw std::runtime_error (folder + ": no .png or .jpg person crops");
  PeopleCrops crops;
  crops.person = person;
  for (const fs::path &file : files)
  {
    cv::Mat grey = readImage (file.string (), cv::IMREAD_GRAYSCALE);
    if (!crops.images.empty () && grey.size () != crops.images.front ().size ())
      throw std::runtime_error (file.string () + ": " + std::to_string (grey.cols) + "x" + std::to_string (grey.rows) +
                                ", unlike the folder's first crop (" + std::to_string (crops.images.front ().cols) + "x" +
                                std::to_string (crops.images.front ().rows) + ")");
    crops.images.push_back (grey);
    crops.names.push_back (file.filename ().string ());
  }
  const cv::Rect frame (0, 0, crops.images.front ().cols, crops.images.front ().rows);
  if (person.width < 8 || person.height < 8 || (person & frame) != person)
    throw std::runtime_error (folder + ": the person box " + std::to_string (person.x) + "," + std::to_string (person.y) + " " +
                              std::to_string (person.width) + "x" + std::to_string (person.height) +
                              " is not inside the crops (" + std::to_string (frame.width) + "x" +
                              std::to_string (frame.height) + ") or smaller than 8 pixels");
  return crops;
}

std::vector<std::size_t>
foldIndices (std::size_t count, int folds, int fold, bool test)
{
  std::vector<std::size_t> groups (count);
  for (std::size_t i = 0; i < count; ++i)
    groups[i] = i;
  return foldIndices (groups, folds, fold, test);
}

std::vector<std::size_t>
foldIndices (const std::vector<std::size_t> &groups, int folds, int fold, bool test)
{
  if (folds < 2 || folds > 100 || fold < -1 || fold >= folds)
    throw std::invalid_argument ("folds: 2 to 100 folds, and a fold from -1 (none) to folds - 1");
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < groups.size (); ++i)
    if ((fold >= 0 && static_cast<int> (groups[i] % folds) == fold) == test)
      out.push_back (i);
  return out;
}

std::vector<std::size_t>
cropSourcePhotos (const std::vector<std::string> &names)
{
  std::vector<std::size_t> groups;
  std::unordered_map<std::string, std::size_t> photos;  // stem -> its number, in order of first sight
  for (const std::string &name : names)
  {
    std::string stem = std::filesystem::path (name).stem ().string ();
    // crop001001a: the photo crop001001; a name ending in a digit (or one letter alone) is kept.
    if (stem.size () >= 2 && std::islower (static_cast<unsigned char> (stem.back ())) &&
        std::isdigit (static_cast<unsigned char> (stem[stem.size () - 2])))
      stem.pop_back ();
    groups.push_back (photos.emplace (std::move (stem), photos.size ()).first->second);
  }
  return groups;
}

PeopleImages
pasteCrops (const std::vector<AnnotatedImage> &backgrounds, const std::vector<std::size_t> &background_which,
            const PeopleCrops &crops, const std::vector<std::size_t> &which, const PastedCropsParams &params)
{
  const PastedCropsParams &p = params;
  if (p.min_height < 16 || p.min_height > p.max_height || p.max_height > 2000 || p.min_background_height < 16 ||
      p.min_background_height > p.max_background_height || p.max_background_height > 4000)
    throw std::invalid_argument ("pasted crops: heights must satisfy 16 <= min <= max <= 2000 (people) and 16 <= min <= "
                                 "max <= 4000 (backgrounds) pixels");
  if (p.people_per_image < 1 || p.people_per_image > 10 || !(p.min_feet >= 0 && p.min_feet <= 1))
    throw std::invalid_argument ("pasted crops: 1 to 10 people per image, min_feet in [0, 1]");
  PeopleImages result;
  if (which.empty () || crops.images.empty ())
    return result;
  const cv::Size crop_size = crops.images.front ().size ();
  const cv::Rect &person = crops.person;
  // The crop's margin round the person fades into the background over most of its width.
  const int margin = std::min ({person.x, person.y, crop_size.width - person.br ().x, crop_size.height - person.br ().y});
  const double fade = std::max (1.0, 0.75 * margin);
  cv::Mat alpha (crop_size, CV_32F);
  for (int y = 0; y < crop_size.height; ++y)
    for (int x = 0; x < crop_size.width; ++x)
    {
      const int edge = std::min ({x, y, crop_size.width - 1 - x, crop_size.height - 1 - y});
      alpha.at<float> (y, x) = static_cast<float> (std::min (1.0, (edge + 0.5) / fade));
    }
  std::size_t next = 0;
  for (std::size_t b = 0; b < background_which.size (); ++b)
  {
    const AnnotatedImage &source = backgrounds.at (background_which[b]);
    const cv::Mat grey = toGrey (source.grey);
    if (grey.empty ())
      continue;
    const double wanted = p.min_background_height + (p.max_background_height - p.min_background_height) * detail::goldenSpread (b);
    const double k = std::min (1.0, wanted / grey.rows);
    cv::Mat canvas;
    cv::resize (grey, canvas, cv::Size (std::max (1, cvRound (grey.cols * k)), std::max (1, cvRound (grey.rows * k))), 0, 0,
                k < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    std::vector<cv::Rect> ignore, boxes;
    for (const AnnotatedPerson &someone : source.people)
      ignore.push_back (scaledRect (someone.tight_box, k));
    for (const cv::Rect &region : source.ignored)
      ignore.push_back (scaledRect (region, k));
    std::vector<cv::Rect> taken = ignore;
    std::mt19937 rng (static_cast<unsigned> (b * 7919 + 17));
    for (int n = 0; n < p.people_per_image; ++n)
    {
      const std::size_t c = which[next++ % which.size ()];
      const double vary = 1.0 + 0.3 * (std::fmod (0.5 + 0.7548776662466927 * static_cast<double> (n), 1.0) - 0.5);
      double height = std::clamp ((p.min_height + (p.max_height - p.min_height) * detail::goldenSpread (b)) * vary,
                                  static_cast<double> (p.min_height), static_cast<double> (p.max_height));
      // The whole crop must fit into the canvas.
      height = std::min ({height, (canvas.rows - 1.0) * person.height / crop_size.height,
                          (canvas.cols - 1.0) * person.height / crop_size.width});
      const double s = height / person.height;
      const cv::Size size (cvRound (crop_size.width * s), cvRound (crop_size.height * s));
      if (height < 8 || size.width < 2 || size.height < 2 || size.width >= canvas.cols || size.height >= canvas.rows)
        continue;
      std::uniform_int_distribution<int> x_of (0, canvas.cols - size.width);
      const int person_bottom = cvRound (person.br ().y * s), below = size.height - person_bottom;
      const int lowest_feet = std::max (person_bottom, static_cast<int> (std::lround (p.min_feet * canvas.rows)));
      const int highest_feet = canvas.rows - below;
      std::uniform_int_distribution<int> feet_of (std::min (lowest_feet, highest_feet), highest_feet);
      // The crop goes at where; the person inside it is what must not collide.
      const cv::Rect best = detail::leastCollidingPlace (
          [&] {
            const cv::Rect where (x_of (rng), feet_of (rng) - person_bottom, size.width, size.height);
            const cv::Rect box (where.x + cvRound (person.x * s), where.y + cvRound (person.y * s),
                                cvRound (person.width * s), cvRound (person.height * s));
            return std::make_pair (where, box);
          },
          taken);
      cv::Mat scaled_crop, scaled_alpha;
      const int interpolation = s < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR;
      cv::resize (crops.images[c], scaled_crop, size, 0, 0, interpolation);
      cv::resize (alpha, scaled_alpha, size, 0, 0, cv::INTER_LINEAR);
      for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x)
        {
          const float a = scaled_alpha.at<float> (y, x);
          unsigned char &out = canvas.at<unsigned char> (best.y + y, best.x + x);
          out = cv::saturate_cast<unsigned char> (a * scaled_crop.at<unsigned char> (y, x) + (1.f - a) * out);
        }
      const cv::Rect box (best.x + cvRound (person.x * s), best.y + cvRound (person.y * s), cvRound (person.width * s),
                          cvRound (person.height * s));
      boxes.push_back (box);
      taken.push_back (box);
    }
    result.images.push_back (canvas);
    result.boxes.push_back (boxes);
    result.ignore.push_back (ignore);
  }
  return result;
}

std::vector<cv::Rect>
peopleFreeRegions (const AnnotatedImage &image, const PeopleFreeParams &params)
{
  if (!(params.dilation >= 0 && params.dilation <= 2) || !(params.min_width > 0 && params.min_width <= 1) ||
      !(params.min_height > 0 && params.min_height <= 1) || params.min_region_height < 16 ||
      params.min_region_height > params.max_region_height || params.max_region_height > 4000)
    throw std::invalid_argument ("people-free regions: dilation in [0, 2], minimum sizes in (0, 1], region heights "
                                 "16 <= min <= max <= 4000 pixels");
  std::vector<cv::Rect> regions;
  const cv::Size size = image.grey.size ();
  if (size.area () == 0)
    return regions;
  std::vector<bool> columns (size.width, false), rows (size.height, false);
  const auto mark = [&] (const cv::Mat &mask, int height) {
    const int grow = static_cast<int> (std::ceil (params.dilation * height));
    markGrown (mask, grow, true, columns);
    markGrown (mask, grow, false, rows);
  };
  for (const AnnotatedPerson &person : image.people)
  {
    cv::Mat mask = cv::Mat::zeros (size, CV_8UC1);
    std::vector<cv::Point> polygon;
    for (const cv::Point2f &q : person.landmarks)
      polygon.emplace_back (cvRound (q.x), cvRound (q.y));
    if (polygon.size () >= 3)
      cv::fillPoly (mask, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar (255));
    // The box as well: the outline may miss a few pixels of the person the box holds.
    cv::rectangle (mask, person.tight_box & cv::Rect (cv::Point (), size), cv::Scalar (255), cv::FILLED);
    mark (mask, std::max (person.tight_box.height, 1));
  }
  for (const cv::Rect &region : image.ignored)
  {
    cv::Mat mask = cv::Mat::zeros (size, CV_8UC1);
    cv::rectangle (mask, region & cv::Rect (cv::Point (), size), cv::Scalar (255), cv::FILLED);
    mark (mask, std::max (region.height, 1));
  }
  const int min_width = static_cast<int> (std::ceil (params.min_width * size.height));
  const int min_height = static_cast<int> (std::ceil (params.min_height * size.height));
  const auto runs = [] (const std::vector<bool> &taken, int min_length, const auto &make) {
    int start = -1;
    for (int i = 0; i <= static_cast<int> (taken.size ()); ++i)
    {
      const bool free = i < static_cast<int> (taken.size ()) && !taken[i];
      if (free && start < 0)
        start = i;
      if (!free && start >= 0)
      {
        if (i - start >= min_length)
          make (start, i - start);
        start = -1;
      }
    }
  };
  runs (columns, min_width, [&] (int x, int width) { regions.emplace_back (x, 0, width, size.height); });
  // A whole free image is one region, not a column and a row band.
  if (!(regions.size () == 1 && regions.front ().size () == size))
    runs (rows, min_height, [&] (int y, int height) { regions.emplace_back (0, y, size.width, height); });
  return regions;
}

PeopleImages
peopleFreeImages (const std::vector<AnnotatedImage> &images, const std::vector<std::size_t> &which,
                  const PeopleFreeParams &params)
{
  PeopleImages result;
  std::size_t n = 0;
  for (const std::size_t i : which)
  {
    const cv::Mat grey = toGrey (images.at (i).grey);
    for (const cv::Rect &region : peopleFreeRegions (images[i], params))
    {
      const double wanted = params.min_region_height + (params.max_region_height - params.min_region_height) * detail::goldenSpread (n++);
      const double k = std::min (1.0, wanted / region.height);
      cv::Mat cut;
      cv::resize (grey (region), cut, cv::Size (std::max (1, cvRound (region.width * k)), std::max (1, cvRound (region.height * k))),
                  0, 0, k < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
      result.images.push_back (cut);
      result.boxes.emplace_back ();
      result.ignore.emplace_back ();
    }
  }
  return result;
}
}  // namespace agex

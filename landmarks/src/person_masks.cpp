#include <agex/landmarks/person_masks.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

namespace agex
{
std::vector<std::uint32_t>
cocoRleCountsFromString (const std::string &s)
{
  std::vector<std::uint32_t> counts;
  std::size_t p = 0;
  while (p < s.size ())
  {
    std::int64_t x = 0;
    int k = 0;
    bool more = true;
    while (more)
    {
      if (p >= s.size ())
        throw std::invalid_argument ("the RLE string ends inside a count (at character " + std::to_string (p) + ")");
      const int c = static_cast<unsigned char> (s[p]) - 48;
      if (c < 0 || c > 63)
        throw std::invalid_argument (std::string ("character '") + s[p] + "' at " + std::to_string (p) +
                                     " is not part of a COCO RLE string ('0' to 'o')");
      // 7 groups of 5 bits hold any 32-bit count and its difference to another.
      if (k >= 7)
        throw std::invalid_argument ("a count of the RLE string is too long (at character " + std::to_string (p) + ")");
      x |= static_cast<std::int64_t> (c & 0x1f) << (5 * k);
      more = (c & 0x20) != 0;
      ++p;
      ++k;
      if (!more && (c & 0x10))
        x -= std::int64_t (1) << (5 * k);  // the last group's 0x10 is the sign: x - 2^bits
    }
    if (counts.size () > 2)
      x += counts[counts.size () - 2];
    if (x < 0 || x > std::numeric_limits<std::uint32_t>::max ())
      throw std::invalid_argument ("count " + std::to_string (counts.size ()) + " of the RLE string is " +
                                   std::to_string (x) + ", not a run length");
    counts.push_back (static_cast<std::uint32_t> (x));
  }
  return counts;
}

std::string
cocoRleString (const std::vector<std::uint32_t> &counts)
{
  std::string s;
  for (std::size_t i = 0; i < counts.size (); ++i)
  {
    std::int64_t x = counts[i];
    if (i > 2)
      x -= counts[i - 2];
    bool more = true;
    while (more)
    {
      int c = static_cast<int> (x & 0x1f);
      x >>= 5;  // arithmetic shift: negative differences stay negative
      more = (c & 0x10) ? x != -1 : x != 0;
      if (more)
        c |= 0x20;
      s += static_cast<char> (c + 48);
    }
  }
  return s;
}

cv::Mat
maskFromCocoRle (const std::vector<std::uint32_t> &counts, int height, int width)
{
  if (height <= 0 || width <= 0)
    throw std::invalid_argument ("RLE size " + std::to_string (height) + "x" + std::to_string (width) +
                                 " is not a positive height and width");
  const std::uint64_t pixels = static_cast<std::uint64_t> (height) * static_cast<std::uint64_t> (width);
  std::uint64_t sum = 0;
  for (const std::uint32_t c : counts)
    sum += c;
  if (sum != pixels)
    throw std::invalid_argument ("the RLE counts add up to " + std::to_string (sum) + " pixels, not the " +
                                 std::to_string (height) + " x " + std::to_string (width) + " = " +
                                 std::to_string (pixels) + " of its size");
  // Column-major: fill the transposed image row by row, then transpose.
  cv::Mat columns (width, height, CV_8UC1, cv::Scalar (0));
  unsigned char *out = columns.ptr<unsigned char> ();
  std::uint64_t at = 0;
  for (std::size_t i = 0; i < counts.size (); ++i)
  {
    if (i % 2 == 1)
      std::fill (out + at, out + at + counts[i], static_cast<unsigned char> (255));
    at += counts[i];
  }
  cv::Mat mask;
  cv::transpose (columns, mask);
  return mask;
}

std::vector<std::uint32_t>
cocoRleFromMask (const cv::Mat &mask)
{
  cv::Mat columns;
  cv::transpose (mask != 0, columns);
  columns = columns.clone ();  // continuous
  std::vector<std::uint32_t> counts;
  unsigned char value = 0;
  std::uint32_t run = 0;
  const unsigned char *p = columns.ptr<unsigned char> ();
  for (std::size_t i = 0; i < columns.total (); ++i)
  {
    const unsigned char v = p[i] ? 255 : 0;
    if (v != value)
    {
      counts.push_back (run);
      run = 0;
      value = v;
    }
    ++run;
  }
  counts.push_back (run);
  return counts;
}

namespace
{
void
requireLabelImage (const cv::Mat &labels, const char *what)
{
  if (labels.empty () || (labels.type () != CV_8UC1 && labels.type () != CV_16UC1))
    throw std::invalid_argument (std::string (what) + " must be a non-empty 8- or 16-bit single-channel image");
}

// The first pixel of each component label (components are 1..n).
std::vector<cv::Point>
firstPixels (const cv::Mat &components, int n)
{
  std::vector<cv::Point> first (n + 1, cv::Point (-1, -1));
  int missing = n;
  for (int y = 0; y < components.rows && missing > 0; ++y)
  {
    const int *row = components.ptr<int> (y);
    for (int x = 0; x < components.cols; ++x)
      if (row[x] > 0 && first[row[x]].x < 0)
      {
        first[row[x]] = cv::Point (x, y);
        --missing;
      }
  }
  return first;
}

bool
allInOneComponent (const cv::Mat &mask, const std::vector<cv::Point> &seeds)
{
  cv::Mat components;
  cv::connectedComponents (mask, components, 8, CV_32S);
  for (const cv::Point &p : seeds)
    if (components.at<int> (p) != components.at<int> (seeds.front ()))
      return false;
  return true;
}

cv::Mat
closed (const cv::Mat &binary, int radius)
{
  cv::Mat padded;
  cv::copyMakeBorder (binary, padded, radius, radius, radius, radius, cv::BORDER_CONSTANT, 0);
  cv::morphologyEx (padded, padded, cv::MORPH_CLOSE,
                    cv::getStructuringElement (cv::MORPH_ELLIPSE, cv::Size (2 * radius + 1, 2 * radius + 1)));
  return padded (cv::Rect (radius, radius, binary.cols, binary.rows)).clone ();
}
}  // namespace

LabelMapPerson
personFromLabelMap (const cv::Mat &labels, const std::vector<int> &excluded)
{
  requireLabelImage (labels, "a label map");
  LabelMapPerson result;
  const cv::Mat full = labels != 0;
  cv::Mat excluded_pixels = cv::Mat::zeros (labels.size (), CV_8UC1);
  for (const int label : excluded)
    if (label != 0)
      excluded_pixels |= labels == label;
  const cv::Mat body = full & ~excluded_pixels;
  if (cv::countNonZero (full) == 0)
  {
    result.problem = "empty mask (no labelled pixel)";
    return result;
  }
  if (cv::countNonZero (body) == 0)
  {
    result.problem = "only excluded labels in the mask";
    return result;
  }
  result.mask = body;
  cv::Mat pieces, stats, centroids;
  const int n = cv::connectedComponentsWithStats (body, pieces, stats, centroids, 8, CV_32S) - 1;
  if (n <= 1 || cv::countNonZero (excluded_pixels) == 0)
    return result;
  int largest = 1;
  for (int i = 2; i <= n; ++i)
    if (stats.at<int> (i, cv::CC_STAT_AREA) > stats.at<int> (largest, cv::CC_STAT_AREA))
      largest = i;
  // The pieces the excluded labels joined: those in the largest piece's component of the
  // whole labelled region.
  cv::Mat regions;
  cv::connectedComponents (full, regions, 8, CV_32S);
  const std::vector<cv::Point> first = firstPixels (pieces, n);
  const int region = regions.at<int> (first[largest]);
  std::vector<cv::Point> seeds{first[largest]};
  for (int i = 1; i <= n; ++i)
    if (i != largest && regions.at<int> (first[i]) == region)
      seeds.push_back (first[i]);
  if (seeds.size () == 1)
    return result;
  const cv::Mat bridgeable = excluded_pixels & (regions == region);
  const int body_height = cv::boundingRect (body).height;
  for (int radius = 1; radius <= std::max (1, body_height / 4); radius = std::max (radius + 1, radius * 3 / 2))
  {
    const cv::Mat bridge = closed (body, radius) & bridgeable;
    const cv::Mat joined = body | bridge;
    if (allInOneComponent (joined, seeds))
    {
      result.mask = joined;
      result.bridged_pixels = cv::countNonZero (bridge);
      return result;
    }
  }
  result.mask = body | bridgeable;
  result.bridged_pixels = cv::countNonZero (bridgeable);
  result.whole_excluded_region_kept = true;
  return result;
}

std::vector<std::pair<int, cv::Mat>>
peopleFromInstanceMask (const cv::Mat &instances)
{
  requireLabelImage (instances, "an instance mask");
  std::set<int> values;
  for (int y = 0; y < instances.rows; ++y)
    for (int x = 0; x < instances.cols; ++x)
    {
      const int v = instances.type () == CV_8UC1 ? instances.at<unsigned char> (y, x) : instances.at<std::uint16_t> (y, x);
      if (v > 0)
        values.insert (v);
    }
  std::vector<std::pair<int, cv::Mat>> people;
  for (const int v : values)
    people.emplace_back (v, instances == v);
  return people;
}
}  // namespace agex

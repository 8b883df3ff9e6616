#pragma once
// dlib/imglab image dataset metadata (XML): images, boxes and named parts. Read and
// written without dlib so that users can keep annotating our files in imglab.

#include <opencv2/core.hpp>

#include <map>
#include <string>
#include <vector>

namespace agex
{
/** Box and part coordinates of an imglab file lie within +-1e6 pixels (sizes within 1e6). */
constexpr double kMaxImglabCoordinate = 1e6;

/** One object box of an imglab dataset. Part coordinates are image pixels. */
struct ImglabBox
{
  cv::Rect rect;
  std::string label;
  bool ignore = false;
  std::map<std::string, cv::Point2f> parts;
  int line = 0;  ///< line of the <box> element in the file read (0: not read from a file)
};

struct ImglabImage
{
  std::string file;  ///< as written in the XML: relative paths are relative to the XML's folder
  std::vector<ImglabBox> boxes;
};

struct ImglabDataset
{
  std::string name;
  std::string comment;
  std::vector<ImglabImage> images;
};

/** Reads an imglab XML file. Unknown elements and attributes are skipped; numbers beyond
  * kMaxImglabCoordinate are refused.
  * \throws std::runtime_error naming the file, the line and the problem */
ImglabDataset readImglabDataset (const std::string &path);

/** The XML text of a dataset (what writeImglabDataset writes). Part coordinates are
  * rounded to whole pixels, as imglab stores them. */
std::string imglabDatasetXml (const ImglabDataset &dataset);

/** Writes the dataset atomically. */
void writeImglabDataset (const std::string &path, const ImglabDataset &dataset);

/** The path of an image entry as seen from here: file relative to the XML's folder. */
std::string resolveImglabImagePath (const std::string &dataset_path, const std::string &file);
}  // namespace agex

#include <agex/landmarks/annotation_sources.h>

#include <agex/landmarks/image_files.h>
#include <agex/landmarks/landmark_dataset.h>
#include <agex/landmarks/person_masks.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

namespace fs = std::filesystem;

namespace agex
{
ImglabBox
imglabBox (const ContourAnnotation &annotation)
{
  ImglabBox box;
  box.rect = annotation.box;
  box.label = "person";
  for (int i = 0; i < kContourLandmarkCount; ++i)
    box.parts[contourLandmarkName (i)] = annotation.landmarks[i];
  return box;
}

ImglabBox
imglabIgnoreBox (const cv::Rect &box)
{
  return ImglabBox{squareBox (box), "person", true, {}};
}

// ---- COCO

namespace
{
/** Ids of COCO files (JSON integers; nlohmann reads them as 64-bit). */
constexpr std::int64_t kMinId = std::numeric_limits<long>::min (), kMaxId = std::numeric_limits<long>::max ();

/** Pixel coordinates of COCO files are within this (as imglab's, kMaxImglabCoordinate). */
constexpr double kMaxCocoCoordinate = 1e6;

// Numbers are taken into their real type with a range check: nlohmann's get<float> makes 1e300
// infinite, get<int> truncates 2.5 and get<std::uint32_t> wraps 2^32 + 5 to 5.

/** A JSON number that is a pixel coordinate (finite, within kMaxCocoCoordinate). */
double
cocoCoordinate (const nlohmann::json &v, const std::string &field)
{
  if (!v.is_number () || !(std::abs (v.get<double> ()) <= kMaxCocoCoordinate))
    throw std::runtime_error (field + " " + v.dump () + " is not a pixel coordinate (a number within +-1e6)");
  return v.get<double> ();
}

/** A JSON number that is a whole number in [lo, hi]. */
std::int64_t
cocoWhole (const nlohmann::json &v, std::int64_t lo, std::int64_t hi, const std::string &field)
{
  if (v.is_number_integer ())
  {
    // Unsigned values above 2^63 must not wrap to negative ones.
    if (v.is_number_unsigned () ? v.get<std::uint64_t> () <= static_cast<std::uint64_t> (hi)
                                : v.get<std::int64_t> () >= lo && v.get<std::int64_t> () <= hi)
      return v.get<std::int64_t> ();
  }
  else if (v.is_number_float ())
  {
    const double d = v.get<double> ();
    if (d == std::floor (d) && d >= static_cast<double> (lo) && d <= static_cast<double> (hi))
      return static_cast<std::int64_t> (d);
  }
  throw std::runtime_error (field + " " + v.dump () + " is not a whole number in [" + std::to_string (lo) + ", " +
                            std::to_string (hi) + "]");
}

// A COCO bbox [x, y, width, height]; nonsense is refused rather than cast (undefined
// behaviour for huge values) into a box the dataset readers would reject later.
cv::Rect
cocoBox (const nlohmann::json &bbox, const std::string &where)
{
  if (!bbox.is_array () || bbox.size () != 4)
    throw std::runtime_error (where + ": bbox is not [x, y, width, height]");
  double v[4];
  for (int i = 0; i < 4; ++i)
    v[i] = cocoCoordinate (bbox[i], where + ": bbox " + bbox.dump () + ": value");
  if (v[2] < 0 || v[3] < 0)
    throw std::runtime_error (where + ": bbox " + bbox.dump () + " has a negative size");
  return cv::Rect (static_cast<int> (v[0]), static_cast<int> (v[1]), static_cast<int> (v[2]), static_cast<int> (v[3]));
}

nlohmann::json
readJsonFile (const std::string &path)
{
  std::ifstream in (path);
  if (!in)
    throw std::runtime_error (path + ": cannot open");
  try
  {
    nlohmann::json doc;
    in >> doc;
    return doc;
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error (path + ": not valid JSON (" + std::string (e.what ()) + ")");
  }
}

CocoPerson
cocoPerson (const nlohmann::json &a, const std::string &where)
{
  CocoPerson person;
  person.id = a.value ("id", -1L);
  person.bbox = cocoBox (a.at ("bbox"), where);
  person.crowd = a.value ("iscrowd", 0) != 0;
  person.num_keypoints = a.value ("num_keypoints", 0);
  if (a.contains ("keypoints"))
  {
    const nlohmann::json &k = a["keypoints"];
    if (!k.is_array ())
      throw std::runtime_error (where + ": keypoints are not an array");
    for (std::size_t i = 0; i + 2 < k.size (); i += 3)
      person.keypoints.emplace_back (static_cast<float> (cocoCoordinate (k[i], where + ": keypoint x")),
                                     static_cast<float> (cocoCoordinate (k[i + 1], where + ": keypoint y")),
                                     static_cast<float> (cocoWhole (k[i + 2], 0, 2, where + ": keypoint visibility")));
  }
  if (a.contains ("segmentation"))
    person.segmentation = a["segmentation"];
  return person;
}
}  // namespace

std::vector<CocoImage>
readCocoPeople (const std::string &json_path)
{
  const nlohmann::json coco = readJsonFile (json_path);
  if (!coco.is_object () || !coco.contains ("images") || !coco.contains ("annotations"))
    throw std::runtime_error (json_path + ": no 'images' or 'annotations' (not a COCO file)");
  if (!coco["images"].is_array () || !coco["annotations"].is_array ())
    throw std::runtime_error (json_path + ": 'images' and 'annotations' must be arrays");
  // Where in the JSON we are, so that a malformed entry is reported with its place.
  std::string where = "'categories'";
  try
  {
    std::set<long> person_categories;
    bool categories_listed = false;
    if (coco.contains ("categories") && coco["categories"].is_array ())
      for (const auto &c : coco["categories"])
      {
        categories_listed = true;
        if (c.value ("name", std::string ()) == "person")
          person_categories.insert (cocoWhole (c.at ("id"), kMinId, kMaxId, "category id"));
      }
    std::vector<CocoImage> images;
    std::map<long, std::size_t> by_id;
    for (const auto &entry : coco["images"])
    {
      where = "image " + entry.value ("id", nlohmann::json (-1)).dump ();
      CocoImage image;
      image.id = cocoWhole (entry.at ("id"), kMinId, kMaxId, "id");
      image.file = entry.at ("file_name").get<std::string> ();
      image.width = entry.value ("width", 0);
      image.height = entry.value ("height", 0);
      by_id[image.id] = images.size ();
      images.push_back (std::move (image));
    }
    for (const auto &a : coco["annotations"])
    {
      where = "annotation " + a.value ("id", nlohmann::json (-1)).dump ();
      if (categories_listed && a.contains ("category_id") &&
          !person_categories.count (cocoWhole (a["category_id"], kMinId, kMaxId, "category_id")))
        continue;
      const auto image = by_id.find (cocoWhole (a.at ("image_id"), kMinId, kMaxId, "image_id"));
      if (image == by_id.end ())
        throw std::runtime_error (json_path + ": " + where + ": image_id " + a["image_id"].dump () +
                                  " is not in 'images'");
      images[image->second].people.push_back (cocoPerson (a, json_path + ": " + where));
    }
    return images;
  }
  catch (const nlohmann::json::exception &e)
  {
    throw std::runtime_error (json_path + ": " + where + ": " + e.what ());
  }
  catch (const std::runtime_error &e)
  {
    const std::string message = e.what ();
    if (message.rfind (json_path, 0) == 0)
      throw;
    throw std::runtime_error (json_path + ": " + where + ": " + message);
  }
}

cv::Mat
cocoPersonMask (const CocoPerson &person, const cv::Size &image_size, const std::string &where)
{
  const nlohmann::json &s = person.segmentation;
  try
  {
    if (s.is_array ())
    {
      if (s.empty ())
        return cv::Mat ();
    {
      std::vector<std::vector<float>> polygons;
      for (const auto &polygon : s)
      {
        if (!polygon.is_array ())
          throw std::runtime_error ("segmentation polygon " + polygon.dump ().substr (0, 80) + " is not an array");
        polygons.emplace_back ();
        for (const auto &v : polygon)
          polygons.back ().push_back (static_cast<float> (cocoCoordinate (v, "polygon vertex coordinate")));
      }
      return maskFromPolygons (image_size, polygons);
    }
    }
    if (!s.is_object ())
      return cv::Mat ();
    if (!s.contains ("counts") || !s.contains ("size") || !s["size"].is_array () || s["size"].size () != 2)
      throw std::runtime_error ("segmentation is neither polygons nor an RLE object with 'counts' and 'size'");
    const int height = static_cast<int> (cocoWhole (s["size"][0], 0, 1 << 24, "RLE size[0] (height)"));
    const int width = static_cast<int> (cocoWhole (s["size"][1], 0, 1 << 24, "RLE size[1] (width)"));
    if (height != image_size.height || width != image_size.width)
      throw std::runtime_error ("the RLE mask is " + std::to_string (width) + "x" + std::to_string (height) +
                                " (size [h, w] = " + s["size"].dump () + "), the image " +
                                std::to_string (image_size.width) + "x" + std::to_string (image_size.height));
    std::vector<std::uint32_t> counts;
    if (s["counts"].is_string ())
      counts = cocoRleCountsFromString (s["counts"].get<std::string> ());
    else if (s["counts"].is_array ())
      for (const auto &c : s["counts"])
        counts.push_back (static_cast<std::uint32_t> (
          cocoWhole (c, 0, std::int64_t (height) * width, "RLE count " + std::to_string (counts.size ()))));
    else
      throw std::runtime_error ("RLE counts are neither a string nor an array");
    return maskFromCocoRle (counts, height, width);
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error (where + ": " + e.what ());
  }
}

// ---- Mask folders

namespace
{
bool
isImageFile (const fs::path &path)
{
  std::string ext = path.extension ().string ();
  std::transform (ext.begin (), ext.end (), ext.begin (), [] (unsigned char c) { return std::tolower (c); });
  static const std::set<std::string> known{".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm"};
  return known.count (ext) > 0;
}

std::vector<fs::path>
filesIn (const std::string &dir)
{
  std::error_code error;
  if (!fs::is_directory (dir, error))
    throw std::runtime_error (dir + ": not a folder");
  std::vector<fs::path> files;
  for (const auto &entry : fs::directory_iterator (dir, error))
    if (entry.is_regular_file ())
      files.push_back (entry.path ());
  if (error)
    throw std::runtime_error (dir + ": cannot list the folder: " + error.message ());
  std::sort (files.begin (), files.end ());
  return files;
}
}  // namespace

std::vector<MaskedImage>
pairImagesWithMasks (const std::string &images_dir, const std::string &masks_dir, std::vector<std::string> &without_mask)
{
  std::error_code error;
  const bool same_folder = fs::equivalent (images_dir, masks_dir, error);
  std::set<fs::path> masks;
  for (const fs::path &file : filesIn (masks_dir))
    masks.insert (file.filename ());
  std::vector<MaskedImage> pairs;
  for (const fs::path &image : filesIn (images_dir))
  {
    const std::string stem = image.stem ().string ();
    if (!isImageFile (image) || (same_folder && stem.size () > 5 && stem.compare (stem.size () - 5, 5, "_mask") == 0))
      continue;
    // In a shared folder an image's own name would be its mask.
    std::string mask;
    for (const std::string &name : {stem + ".png", stem + "_mask.png"})
      if (masks.count (name) && !(same_folder && name == image.filename ().string ()) && mask.empty ())
        mask = (fs::path (masks_dir) / name).string ();
    if (mask.empty ())
      without_mask.push_back (image.string ());
    else
      pairs.push_back ({image.string (), mask});
  }
  return pairs;
}

namespace
{
// One person mask, outlined; an ignore box over the mask with the reason when it cannot be.
PersonAnnotation
outlinePerson (const cv::Mat &mask, const ContourAnchors &anchors, const ContourAnnotationParams &params,
               int min_height, const std::string &who)
{
  PersonAnnotation person;
  person.who = who;
  const cv::Rect extent = cv::boundingRect (mask);
  if (extent.height < min_height)
  {
    person.ignore_reason = "shorter than " + std::to_string (min_height) + " px";
    person.box = imglabIgnoreBox (extent);
    return person;
  }
  person.annotation = annotateContour (mask, anchors, params);
  if (!person.annotation.ok)
  {
    person.ignore_reason = person.annotation.problem;
    person.box = imglabIgnoreBox (extent);
    return person;
  }
  person.box = imglabBox (person.annotation);
  return person;
}
}  // namespace

MaskedImageAnnotation
annotateMaskedImage (const MaskedImage &pair, const cv::Size &image_size, const MaskAnnotationOptions &options)
{
  MaskedImageAnnotation result;
  const auto leave_out = [&] (const std::string &problem, const std::string &detail) {
    result.problem = problem;
    result.detail = detail;
    return result;
  };
  cv::Mat labels;
  try
  {
    labels = readLabelImage (pair.mask);
  }
  catch (const std::exception &e)
  {
    return leave_out ("unreadable mask", e.what ());
  }
  if (labels.size () != image_size)
    return leave_out ("mask of another size than its image",
                      pair.mask + " is " + std::to_string (labels.cols) + "x" + std::to_string (labels.rows) +
                        ", the image " + std::to_string (image_size.width) + "x" + std::to_string (image_size.height));
  std::vector<std::pair<int, cv::Mat>> people;
  if (options.instances)
    people = peopleFromInstanceMask (labels);
  else
  {
    const LabelMapPerson person = personFromLabelMap (labels, options.excluded_labels);
    if (!person.problem.empty ())
      return leave_out (person.problem, pair.mask);
    people.emplace_back (1, person.mask);
  }
  if (people.empty ())
    return leave_out ("empty mask (no labelled pixel)", pair.mask);
  for (const auto &[k, mask] : people)
    result.people.push_back (outlinePerson (mask, ContourAnchors (), options.contour, options.min_height,
                                            pair.image + (options.instances ? ": person " + std::to_string (k) : std::string ())));
  return result;
}

PersonAnnotation
annotateCocoPerson (const CocoPerson &person, const cv::Size &image_size, int min_height, int min_keypoints,
                    const std::string &where)
{
  const std::string who = where + ": person " + std::to_string (person.id);
  const auto ignore = [&] (const std::string &reason) {
    return PersonAnnotation{who, imglabIgnoreBox (person.bbox), ContourAnnotation (), reason};
  };
  if (person.crowd)
    return ignore ("crowd annotation (iscrowd)");
  if (person.bbox.height < min_height)
    return ignore ("shorter than " + std::to_string (min_height) + " px");
  if (person.num_keypoints < min_keypoints)
    return ignore ("fewer than " + std::to_string (min_keypoints) + " keypoints");
  const cv::Mat mask = cocoPersonMask (person, image_size, who);
  if (mask.empty ())
    return ignore ("no segmentation");
  PersonAnnotation outlined =
    outlinePerson (mask, anchorsFromCocoKeypoints (person.keypoints), ContourAnnotationParams (), 0, who);
  // An ignore box covers COCO's box (the mask's may be a fragment); an outlined person's
  // shoulders (COCO 5 and 6) give the seed's error scale.
  if (outlined.box.ignore)
    outlined.box = imglabIgnoreBox (person.bbox);
  else if (person.keypoints.size () == 17 && person.keypoints[5].z > 0 && person.keypoints[6].z > 0)
    for (int s = 0; s < 2; ++s)
      outlined.box.parts[kShoulderPartNames[s]] = cv::Point2f (person.keypoints[5 + s].x, person.keypoints[5 + s].y);
  return outlined;
}
}  // namespace agex

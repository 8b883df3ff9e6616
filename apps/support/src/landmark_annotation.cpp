#include <agex/apps/landmark_annotation.h>

#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/io/pcd_reader.h>
#include <agex/landmarks/person_masks.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>

#include <boost/program_options/value_semantic.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <set>
#include <sstream>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
po::options_description
annotateOutputOptions (AnnotateOutput &o)
{
  po::options_description d ("Output");
  d.add_options () ("help,h", "show this help") ("out", po::value (&o.out)->required (), "imglab XML to write")
    ("min-height", po::value (&o.min_height)->default_value (o.min_height),
     "people shorter than this (pixels) become ignore boxes")
    ("overlay-dir", po::value (&o.overlay_dir), "write a PNG per image with the annotations drawn here")
    ("name", po::value (&o.name)->default_value ("agex contour landmarks"), "dataset name");
  return d;
}

std::string
pathFromXml (const std::string &xml_path, const std::string &image_path)
{
  std::error_code error;
  const fs::path base = fs::absolute (fs::path (xml_path)).parent_path ();
  const fs::path relative = fs::relative (fs::absolute (image_path), base, error);
  return error || relative.empty () ? fs::absolute (image_path).string () : relative.string ();
}

ImglabBox
annotatedBox (const ContourAnnotation &annotation)
{
  ImglabBox box;
  box.rect = annotation.box;
  box.label = "person";
  for (int i = 0; i < kContourLandmarkCount; ++i)
    box.parts[contourLandmarkName (i)] = annotation.landmarks[i];
  return box;
}

ImglabBox
ignoreBox (const cv::Rect &box)
{
  return ImglabBox{squareBox (box), "person", true, {}};
}

void
writeAnnotationOverlay (const std::string &dir, const std::string &name, const cv::Mat &image,
                        const std::vector<ContourAnnotation> &annotations, const InputFiles &inputs)
{
  std::vector<LandmarkedPerson> people;
  for (const auto &a : annotations)
    people.push_back ({a.box, 1.0, a.landmarks});
  const std::string path = (fs::path (dir) / (fs::path (name).stem ().string () + ".png")).string ();
  inputs.checkOutput (path);
  fs::create_directories (dir);
  writePng (path, renderLandmarkOverlay (image, people));
}

void
AnnotationSummary::ignored (const std::string &where, const std::string &reason, bool print)
{
  ++ignored_;
  ++ignore_reasons_[reason];
  if (print)
    std::cerr << "agex_annotate: " << where << ": ignore box: " << reason << "\n";
}

void
AnnotationSummary::skippedImage (const std::string &file, const std::string &reason, const std::string &detail)
{
  ++skipped_;
  ++skip_reasons_[reason];
  std::cerr << "agex_annotate: " << file << ": left out: " << reason << (detail.empty () ? "" : " (" + detail + ")")
            << "\n";
}

std::string
AnnotationSummary::line (std::size_t images) const
{
  auto reasons = [] (const std::map<std::string, std::size_t> &counts) {
    std::string text;
    for (const auto &[reason, count] : counts)
      text += (text.empty () ? "" : "; ") + reason + ": " + std::to_string (count);
    return text;
  };
  std::ostringstream out;
  out << images << " images, " << outlined_ << " people outlined, " << ignored_ << " ignore boxes";
  if (ignored_ > 0)
    out << " (" << reasons (ignore_reasons_) << ")";
  if (skipped_ > 0)
    out << ", " << skipped_ << " images left out (" << reasons (skip_reasons_) << ")";
  return out.str ();
}

// ---- COCO

namespace
{
// A COCO bbox [x, y, width, height]; nonsense is refused rather than cast (undefined
// behaviour for huge values) into a box the dataset readers would reject later.
cv::Rect
cocoBox (const nlohmann::json &bbox, const std::string &where)
{
  if (!bbox.is_array () || bbox.size () != 4)
    throw std::runtime_error (where + ": bbox is not [x, y, width, height]");
  double v[4];
  for (int i = 0; i < 4; ++i)
  {
    v[i] = bbox[i].get<double> ();
    if (!std::isfinite (v[i]) || std::abs (v[i]) > 1e6)
      throw std::runtime_error (where + ": bbox " + bbox.dump () + " has a value that is not a pixel coordinate");
  }
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
    const auto k = a["keypoints"].get<std::vector<float>> ();
    for (std::size_t i = 0; i + 2 < k.size (); i += 3)
      person.keypoints.emplace_back (k[i], k[i + 1], k[i + 2]);
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
          person_categories.insert (c.at ("id").get<long> ());
      }
    std::vector<CocoImage> images;
    std::map<long, std::size_t> by_id;
    for (const auto &entry : coco["images"])
    {
      where = "image " + entry.value ("id", nlohmann::json (-1)).dump ();
      CocoImage image;
      image.id = entry.at ("id").get<long> ();
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
          !person_categories.count (a["category_id"].get<long> ()))
        continue;
      const auto image = by_id.find (a.at ("image_id").get<long> ());
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
      return maskFromPolygons (image_size, s.get<std::vector<std::vector<float>>> ());
    }
    if (!s.is_object ())
      return cv::Mat ();
    if (!s.contains ("counts") || !s.contains ("size") || !s["size"].is_array () || s["size"].size () != 2)
      throw std::runtime_error ("segmentation is neither polygons nor an RLE object with 'counts' and 'size'");
    const int height = s["size"][0].get<int> (), width = s["size"][1].get<int> ();
    if (height != image_size.height || width != image_size.width)
      throw std::runtime_error ("the RLE mask is " + std::to_string (width) + "x" + std::to_string (height) +
                                " (size [h, w] = " + s["size"].dump () + "), the image " +
                                std::to_string (image_size.width) + "x" + std::to_string (image_size.height));
    const std::vector<std::uint32_t> counts = s["counts"].is_string ()
                                                ? cocoRleCountsFromString (s["counts"].get<std::string> ())
                                                : s["counts"].get<std::vector<std::uint32_t>> ();
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
std::uint32_t
bigEndian32 (const std::string &b, std::size_t at)
{
  return static_cast<std::uint32_t> (static_cast<unsigned char> (b[at])) << 24 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 1])) << 16 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 2])) << 8 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 3]));
}

// The palette of a palette PNG (colour type 3), as BGR; empty for any other file.
std::vector<cv::Vec3b>
pngPalette (const std::string &bytes)
{
  static const char signature[] = "\x89PNG\r\n\x1a\n";
  if (bytes.size () < 33 || bytes.compare (0, 8, signature, 8) != 0 || bytes.compare (12, 4, "IHDR") != 0 ||
      bytes[25] != 3)
    return {};
  std::size_t at = 8;
  while (at + 12 <= bytes.size ())
  {
    const std::uint32_t length = bigEndian32 (bytes, at);
    if (length > bytes.size () - at - 12)
      break;
    if (bytes.compare (at + 4, 4, "PLTE") == 0)
    {
      std::vector<cv::Vec3b> palette;
      for (std::size_t i = 0; i + 2 < length; i += 3)
        palette.emplace_back (bytes[at + 8 + i + 2], bytes[at + 8 + i + 1], bytes[at + 8 + i]);
      return palette;
    }
    at += 12 + length;
  }
  return {};
}
}  // namespace

cv::Mat
readLabelImage (const std::string &path)
{
  const cv::Mat decoded = readImage (path, cv::IMREAD_UNCHANGED, "a mask");
  if (decoded.type () == CV_8UC1 || decoded.type () == CV_16UC1)
    return decoded;
  std::ifstream in (path, std::ios::binary);
  const std::string bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  const std::vector<cv::Vec3b> palette = pngPalette (bytes);
  if (palette.empty () || decoded.type () != CV_8UC3)
    throw std::runtime_error (path + ": a " + std::to_string (decoded.channels ()) +
                              "-channel image, not a mask (label or instance masks are 8 or 16-bit grey, or palette PNGs)");
  // Back from colours to indices; a colour listed twice means its first index (unused
  // palette entries are usually black, like the background at index 0).
  std::map<std::uint32_t, unsigned char> index;
  for (std::size_t i = palette.size (); i-- > 0;)
    index[palette[i][0] << 16 | palette[i][1] << 8 | palette[i][2]] = static_cast<unsigned char> (i);
  cv::Mat labels (decoded.size (), CV_8UC1);
  for (int y = 0; y < decoded.rows; ++y)
    for (int x = 0; x < decoded.cols; ++x)
    {
      const cv::Vec3b c = decoded.at<cv::Vec3b> (y, x);
      const auto it = index.find (c[0] << 16 | c[1] << 8 | c[2]);
      if (it == index.end ())
        throw std::runtime_error (path + ": pixel (" + std::to_string (x) + ", " + std::to_string (y) +
                                  ") has a colour that is not in the PNG's palette");
      labels.at<unsigned char> (y, x) = it->second;
    }
  return labels;
}

cv::Mat
maskSilhouette (const std::string &mask_path, const std::vector<int> &excluded_labels)
{
  const cv::Mat labels = readLabelImage (mask_path);
  cv::Mat silhouette (labels.size (), CV_8UC1, cv::Scalar (40));
  silhouette.setTo (170, labels != 0);
  for (const int label : excluded_labels)
    silhouette.setTo (95, labels == label);
  return silhouette;
}

std::vector<int>
parseLabelList (const std::string &text, const std::string &flag)
{
  std::vector<int> labels;
  std::stringstream in (text);
  std::string item;
  while (std::getline (in, item, ','))
  {
    char *end = nullptr;
    const long value = std::strtol (item.c_str (), &end, 10);
    if (item.empty () || *end != '\0' || value < 1 || value > 65535)
      throw std::runtime_error (flag + " " + text + ": '" + item + "' is not a label (1 to 65535; list them as 2,33,56)");
    labels.push_back (static_cast<int> (value));
  }
  return labels;
}

namespace
{
// Outlines one person mask into out; an ignore box with the reason when it cannot.
void
outlinePerson (const cv::Mat &mask, const ContourAnchors &anchors, const ContourAnnotationParams &params,
               int min_height, const std::string &where, AnnotationSummary &summary, ImglabImage &out,
               std::vector<ContourAnnotation> &drawn)
{
  const cv::Rect extent = cv::boundingRect (mask);
  if (extent.height < min_height)
  {
    summary.ignored (where, "shorter than " + std::to_string (min_height) + " px");
    out.boxes.push_back (ignoreBox (extent));
    return;
  }
  const ContourAnnotation annotation = annotateContour (mask, anchors, params);
  if (!annotation.ok)
  {
    summary.ignored (where, annotation.problem);
    out.boxes.push_back (ignoreBox (extent));
    return;
  }
  out.boxes.push_back (annotatedBox (annotation));
  drawn.push_back (annotation);
  summary.outlined ();
}
}  // namespace

bool
annotateMaskedImage (const MaskedImage &pair, const cv::Size &image_size, const MaskAnnotationOptions &options,
                     AnnotationSummary &summary, ImglabImage &out, std::vector<ContourAnnotation> &drawn)
{
  cv::Mat labels;
  try
  {
    labels = readLabelImage (pair.mask);
  }
  catch (const std::exception &e)
  {
    summary.skippedImage (pair.image, "unreadable mask", e.what ());
    return false;
  }
  if (labels.size () != image_size)
  {
    summary.skippedImage (pair.image, "mask of another size than its image",
                          pair.mask + " is " + std::to_string (labels.cols) + "x" + std::to_string (labels.rows) +
                            ", the image " + std::to_string (image_size.width) + "x" + std::to_string (image_size.height));
    return false;
  }
  std::vector<std::pair<int, cv::Mat>> people;
  if (options.instances)
    people = peopleFromInstanceMask (labels);
  else
  {
    const LabelMapPerson person = personFromLabelMap (labels, options.excluded_labels);
    if (person.problem.empty ())
      people.emplace_back (1, person.mask);
    else
    {
      summary.skippedImage (pair.image, person.problem, pair.mask);
      return false;
    }
  }
  if (people.empty ())
  {
    summary.skippedImage (pair.image, "empty mask (no labelled pixel)", pair.mask);
    return false;
  }
  for (const auto &[k, mask] : people)
    outlinePerson (mask, ContourAnchors (), options.contour, options.min_height,
                   pair.image + (options.instances ? ": person " + std::to_string (k) : std::string ()), summary, out,
                   drawn);
  return true;
}

void
annotateCocoPerson (const CocoPerson &person, const cv::Size &image_size, int min_height, int min_keypoints,
                    const std::string &where, AnnotationSummary &summary, ImglabImage &out,
                    std::vector<ContourAnnotation> &drawn)
{
  const std::string who = where + ": person " + std::to_string (person.id);
  const auto ignore = [&] (const std::string &reason) {
    summary.ignored (who, reason);
    out.boxes.push_back (ignoreBox (person.bbox));
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
  outlinePerson (mask, anchorsFromCocoKeypoints (person.keypoints), ContourAnnotationParams (), 0, who, summary, out,
                 drawn);
  // An ignore box covers COCO's box (the mask's may be a fragment); an outlined person's
  // shoulders (COCO 5 and 6) give the seed's error scale.
  ImglabBox &box = out.boxes.back ();
  if (box.ignore)
    box = ignoreBox (person.bbox);
  else if (person.keypoints.size () == 17 && person.keypoints[5].z > 0 && person.keypoints[6].z > 0)
    for (int s = 0; s < 2; ++s)
      box.parts[kShoulderPartNames[s]] = cv::Point2f (person.keypoints[5 + s].x, person.keypoints[5 + s].y);
}

// ---- RGB-D clouds

cv::Mat
readRgbdFrame (const std::string &path, pcl::PointCloud<pcl::PointXYZ>::Ptr &xyz)
{
  const pcl::PCLPointCloud2 blob = readPcd (path);  // FrameError names the file and the problem
  bool has_colour = false;
  for (const auto &field : blob.fields)
    has_colour = has_colour || field.name == "rgb" || field.name == "rgba";
  pcl::PointCloud<pcl::PointXYZRGBA> cloud;
  pcl::fromPCLPointCloud2 (blob, cloud);
  if (cloud.height < 2)
    throw std::runtime_error (path + ": not an organized cloud (height " + std::to_string (cloud.height) + ")");
  const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
  cv::Mat colour (height, width, CV_8UC3);
  xyz = std::make_shared<pcl::PointCloud<pcl::PointXYZ>> ();
  pcl::copyPointCloud (cloud, *xyz);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const auto &p = cloud.at (u, v);
      if (has_colour)
        colour.at<cv::Vec3b> (v, u) = cv::Vec3b (p.b, p.g, p.r);
      else
      {
        // Depth-only frames (agex_synth) get shaded depth: near bright, 1 m of depth per
        // 50 grey levels, no measurement black.
        const double grey = std::isfinite (p.z) ? std::clamp (255.0 - 50.0 * p.z, 30.0, 255.0) : 0.0;
        colour.at<cv::Vec3b> (v, u) = cv::Vec3b::all (static_cast<unsigned char> (grey));
      }
    }
  return colour;
}

StagingDirectory::StagingDirectory (const std::string &destination)
{
  std::string pattern = (fs::path (destination) / ".agex_staging-XXXXXX").string ();
  if (!::mkdtemp (pattern.data ()))
    throw std::runtime_error (destination + ": cannot create a staging folder: " + std::strerror (errno));
  dir_ = pattern;
}

StagingDirectory::~StagingDirectory ()
{
  std::error_code ignored;
  fs::remove_all (dir_, ignored);
}

std::string
StagingDirectory::path (const std::string &final_path)
{
  staged_.push_back (final_path);
  return (fs::path (dir_) / fs::path (final_path).filename ()).string ();
}

void
StagingDirectory::commit ()
{
  for (const std::string &final_path : staged_)
    fs::rename (fs::path (dir_) / fs::path (final_path).filename (), final_path);
  staged_.clear ();
}
}  // namespace apps
}  // namespace agex

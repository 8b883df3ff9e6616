// agex_annotate: 180-landmark body-contour annotations without a human.
//   agex_annotate coco --json FILE --images DIR --out XML   person masks (COCO polygons)
//   agex_annotate rgbd INPUT... --out XML                     organized XYZRGBA clouds
// Writes a dlib/imglab XML dataset (square boxes, parts 000-179, shoulders when known)
// for agex_landmarks_train, agex_landmarks_eval and imglab.

#include <agex/apps/command_line.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/io/atomic_file.h>
#include <agex/io/pcd_reader.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace
{
// Image paths in the XML are relative to its folder when they can be.
std::string
pathFromXml (const std::string &xml_path, const std::string &image_path)
{
  std::error_code error;
  const fs::path base = fs::absolute (fs::path (xml_path)).parent_path ();
  const fs::path relative = fs::relative (fs::absolute (image_path), base, error);
  return error || relative.empty () ? fs::absolute (image_path).string () : relative.string ();
}

agex::ImglabBox
annotatedBox (const agex::ContourAnnotation &annotation)
{
  agex::ImglabBox box;
  box.rect = annotation.box;
  box.label = "person";
  for (int i = 0; i < agex::kContourLandmarkCount; ++i)
    box.parts[agex::contourLandmarkName (i)] = annotation.landmarks[i];
  return box;
}

void
writeAnnotationOverlay (const std::string &dir, const std::string &name, const cv::Mat &image,
                        const std::vector<agex::ContourAnnotation> &annotations, const agex::InputFiles &read)
{
  std::vector<agex::apps::LandmarkedPerson> people;
  for (const auto &a : annotations)
    people.push_back ({a.box, 1.0, a.landmarks});
  const std::string path = (fs::path (dir) / (fs::path (name).stem ().string () + ".png")).string ();
  read.checkOutput (path);
  fs::create_directories (dir);
  agex::apps::writePng (path, agex::apps::renderLandmarkOverlay (image, people));
}

// Files written into a hidden folder inside their destination and renamed into it on
// commit (); destroyed uncommitted, the folder and what it holds are removed.
class StagingDirectory
{
public:
  explicit StagingDirectory (const std::string &destination) : destination_ (destination)
  {
    std::string pattern = (fs::path (destination) / ".agex_staging-XXXXXX").string ();
    if (!::mkdtemp (pattern.data ()))
      throw std::runtime_error (destination + ": cannot create a staging folder: " + std::strerror (errno));
    dir_ = pattern;
  }
  ~StagingDirectory ()
  {
    std::error_code ignored;
    fs::remove_all (dir_, ignored);
  }
  StagingDirectory (const StagingDirectory &) = delete;
  StagingDirectory &operator= (const StagingDirectory &) = delete;

  /** Where to write the file that will end up at final_path (inside the destination). */
  std::string path (const std::string &final_path)
  {
    staged_.push_back (final_path);
    return (fs::path (dir_) / fs::path (final_path).filename ()).string ();
  }
  void commit ()
  {
    for (const std::string &final_path : staged_)
      fs::rename (fs::path (dir_) / fs::path (final_path).filename (), final_path);
    staged_.clear ();
  }

private:
  std::string destination_, dir_;
  std::vector<std::string> staged_;
};

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

struct CommonOptions
{
  std::string out, overlay_dir, name;
  int min_height = 48;
};

po::options_description
commonDescription (CommonOptions &o)
{
  po::options_description d ("Output");
  d.add_options () ("help,h", "show this help") ("out", po::value (&o.out)->required (), "imglab XML to write")
    ("min-height", po::value (&o.min_height)->default_value (o.min_height),
     "people shorter than this (pixels) become ignore boxes")
    ("overlay-dir", po::value (&o.overlay_dir), "write a PNG per image with the annotations drawn here")
    ("name", po::value (&o.name)->default_value ("agex contour landmarks"), "dataset name");
  return d;
}

int
annotateCoco (int argc, char **argv)
{
  CommonOptions common;
  std::string json_path, images_dir;
  int min_keypoints = 0;
  std::vector<std::string> only;
  po::options_description options ("agex_annotate coco --json FILE --images DIR --out XML [options]\n"
                                   "Contour landmarks from COCO person polygons and keypoints");
  options.add (commonDescription (common));
  options.add_options () ("json", po::value (&json_path)->required (), "COCO annotations (polygon segmentation)")
    ("images", po::value (&images_dir)->required (), "folder with the images")
    ("min-keypoints", po::value (&min_keypoints)->default_value (min_keypoints),
     "people with fewer labelled keypoints become ignore boxes")
    ("only", po::value (&only)->multitoken (), "annotate only these image files (file_name in the JSON)");
  if (!agex::apps::parseCommandLine (argc, argv, options, {}))
    return 0;
  agex::InputFiles read ({json_path});
  read.checkOutput (common.out);

  std::ifstream in (json_path);
  if (!in)
    throw std::runtime_error (json_path + ": cannot open");
  nlohmann::json coco;
  try
  {
    in >> coco;
  }
  catch (const std::exception &e)
  {
    throw std::runtime_error (json_path + ": not valid JSON (" + std::string (e.what ()) + ")");
  }
  if (!coco.is_object () || !coco.contains ("images") || !coco.contains ("annotations"))
    throw std::runtime_error (json_path + ": no 'images' or 'annotations' (not a COCO file)");
  if (!coco["images"].is_array () || !coco["annotations"].is_array ())
    throw std::runtime_error (json_path + ": 'images' and 'annotations' must be arrays");

  agex::ImglabDataset dataset;
  dataset.name = common.name;
  dataset.comment = "agex_annotate coco from " + json_path;
  std::size_t annotated = 0, ignored = 0;
  // Where in the JSON we are, so that a malformed entry is reported with its place.
  std::string where = "'images'";
  try
  {
    std::map<long, std::vector<const nlohmann::json *>> by_image;
    for (const auto &a : coco["annotations"])
    {
      where = "annotation " + a.value ("id", nlohmann::json (-1)).dump ();
      by_image[a.at ("image_id").get<long> ()].push_back (&a);
    }
    // Every image the JSON names is an input: no output may land on one.
    std::set<std::string> named;
    for (const auto &entry : coco["images"])
    {
      where = "image " + entry.value ("id", nlohmann::json (-1)).dump ();
      const std::string file = entry.at ("file_name").get<std::string> ();
      named.insert (file);
      read.add ((fs::path (images_dir) / file).string ());
    }
    read.checkOutput (common.out);
    for (const std::string &file : only)
      if (!named.count (file))
        throw std::runtime_error ("--only " + file + ": no image with that file_name in " + json_path);

    for (const auto &entry : coco["images"])
    {
      const std::string file = entry.at ("file_name").get<std::string> ();
      where = "image " + file;
      if (!only.empty () && std::find (only.begin (), only.end (), file) == only.end ())
        continue;
      const std::string path = (fs::path (images_dir) / file).string ();
      const cv::Mat image = agex::apps::readImage (path, cv::IMREAD_COLOR, "the image named in " + json_path);
      agex::ImglabImage out_image;
      out_image.file = pathFromXml (common.out, path);
      std::vector<agex::ContourAnnotation> drawn;
      for (const nlohmann::json *a : by_image[entry.at ("id").get<long> ()])
      {
        where = "annotation " + a->value ("id", nlohmann::json (-1)).dump () + " of image " + file;
        const cv::Rect coco_box = cocoBox (a->at ("bbox"), json_path + ": " + where);
        agex::ImglabBox ignore_box{agex::squareBox (coco_box), "person", true, {}};
        const bool polygons = a->contains ("segmentation") && (*a)["segmentation"].is_array ();
        if (a->value ("iscrowd", 0) != 0 || !polygons || coco_box.height < common.min_height ||
            a->value ("num_keypoints", 0) < min_keypoints)
        {
          out_image.boxes.push_back (ignore_box);
          ++ignored;
          continue;
        }
        const auto polygon_list = (*a)["segmentation"].get<std::vector<std::vector<float>>> ();
        std::vector<cv::Point3f> keypoints;
        if (a->contains ("keypoints"))
        {
          const auto k = (*a)["keypoints"].get<std::vector<float>> ();
          for (std::size_t i = 0; i + 2 < k.size (); i += 3)
            keypoints.emplace_back (k[i], k[i + 1], k[i + 2]);
        }
        const agex::ContourAnnotation annotation = agex::annotateContour (
          agex::maskFromPolygons (image.size (), polygon_list), agex::anchorsFromCocoKeypoints (keypoints));
        if (!annotation.ok)
        {
          std::cerr << "agex_annotate: " << file << ": person " << a->value ("id", 0L) << " skipped: " << annotation.problem
                    << "\n";
          out_image.boxes.push_back (ignore_box);
          ++ignored;
          continue;
        }
        agex::ImglabBox box = annotatedBox (annotation);
        // Shoulders (COCO 5 and 6) give the seed's error scale.
        if (keypoints.size () == 17 && keypoints[5].z > 0 && keypoints[6].z > 0)
          for (int s = 0; s < 2; ++s)
            box.parts[agex::apps::kShoulderPartNames[s]] = cv::Point2f (keypoints[5 + s].x, keypoints[5 + s].y);
        out_image.boxes.push_back (box);
        drawn.push_back (annotation);
        ++annotated;
      }
      if (!common.overlay_dir.empty ())
        writeAnnotationOverlay (common.overlay_dir, file, image, drawn, read);
      dataset.images.push_back (std::move (out_image));
    }
  }
  catch (const nlohmann::json::exception &e)
  {
    throw std::runtime_error (json_path + ": " + where + ": " + e.what ());
  }
  agex::writeImglabDataset (common.out, dataset);
  std::cout << common.out << ": " << dataset.images.size () << " images, " << annotated << " people annotated, "
            << ignored << " ignore boxes\n";
  return 0;
}

int
annotateRgbd (int argc, char **argv)
{
  CommonOptions common;
  std::vector<std::string> inputs;
  std::string images_dir;
  float min_person_m = 1.0f, max_person_m = 2.3f, max_width_m = 2.0f, max_depth_m = 1.2f;
  int max_people = 0;
  double max_fill = 0.8;
  agex::DepthPipelineParams params;
  // People anywhere in a room, not only at the Bonn distance.
  params.crop_min = Eigen::Vector3f (-6.f, -3.f, 0.5f);
  params.crop_max = Eigen::Vector3f (6.f, 3.f, 10.f);
  std::vector<std::string> vector_flags;
  po::options_description options ("agex_annotate rgbd INPUT... --out XML [options]\n"
                                   "Contour landmarks from organized XYZRGBA clouds (.pcd): the depth stages segment\n"
                                   "each person, AGEX extrema anchor the landmarks on the colour silhouette. Clouds\n"
                                   "without colour (agex_synth frames made without --colour) give a shaded depth image instead.");
  options.add (commonDescription (common));
  options.add_options () ("input", po::value (&inputs)->multitoken (), "organized XYZRGBA PCD files")
    ("images-dir", po::value (&images_dir), "where the colour images are written (default: <out>_images)")
    ("min-person-height", po::value (&min_person_m)->default_value (min_person_m), "metres; shorter meshes are not people")
    ("max-person-height", po::value (&max_person_m)->default_value (max_person_m), "metres; taller meshes are not people")
    ("max-person-width", po::value (&max_width_m)->default_value (max_width_m), "metres; wider meshes are not people")
    ("max-person-depth", po::value (&max_depth_m)->default_value (max_depth_m), "metres; deeper meshes are not people")
    ("max-fill", po::value (&max_fill)->default_value (max_fill),
     "silhouettes filling more of their box are not people (wall strips, boxes)")
    ("max-people", po::value (&max_people)->default_value (max_people),
     "keep the N most central people per frame (0: all), e.g. 1 for agex_synth frames");
  options.add (agex::apps::pipelineOptionsDescription (params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", -1);
  if (!agex::apps::parseCommandLine (argc, argv, options, positional))
    return 0;
  if (inputs.empty ())
    throw std::runtime_error ("no INPUT cloud given (see --help)");
  agex::apps::finishPipelineOptions (vector_flags, params);
  agex::InputFiles read (inputs);
  read.checkOutput (common.out);
  if (images_dir.empty ())
    images_dir = (fs::path (common.out).parent_path () / (fs::path (common.out).stem ().string () + "_images")).string ();
  // One image per input, named after it; inputs of the same name (frames/000000.pcd of two
  // agex_synth runs) get a numbered suffix instead of overwriting each other.
  std::vector<std::string> pngs;
  {
    std::set<std::string> taken;
    for (const std::string &input : inputs)
    {
      const std::string stem = fs::path (input).stem ().string ();
      std::string name = stem + ".png";
      for (int n = 2; !taken.insert (name).second; ++n)
        name = stem + "-" + std::to_string (n) + ".png";
      pngs.push_back ((fs::path (images_dir) / name).string ());
      read.checkOutput (pngs.back ());
    }
  }
  // Overlays must not land on the dataset's own images either.
  agex::InputFiles protected_files = read;
  for (const std::string &png : pngs)
    protected_files.add (png);
  fs::create_directories (images_dir);
  // The images are staged and moved into place only once every frame has worked, so a failed
  // run leaves an earlier dataset's images as they were.
  StagingDirectory staging (images_dir);

  agex::ImglabDataset dataset;
  dataset.name = common.name;
  dataset.comment = "agex_annotate rgbd";
  std::size_t annotated = 0;
  for (std::size_t f = 0; f < inputs.size (); ++f)
  {
    const std::string &input = inputs[f];
    const pcl::PCLPointCloud2 blob = agex::readPcd (input);  // FrameError names the file and the problem
    bool has_colour = false;
    for (const auto &field : blob.fields)
      has_colour = has_colour || field.name == "rgb" || field.name == "rgba";
    pcl::PointCloud<pcl::PointXYZRGBA> cloud;
    pcl::fromPCLPointCloud2 (blob, cloud);
    if (cloud.height < 2)
      throw std::runtime_error (input + ": not an organized cloud (height " + std::to_string (cloud.height) + ")");
    const int width = static_cast<int> (cloud.width), height = static_cast<int> (cloud.height);
    cv::Mat colour (height, width, CV_8UC3);
    auto xyz = std::make_shared<pcl::PointCloud<pcl::PointXYZ>> ();
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
    const agex::DepthPipelineResult result = agex::runDepthPipeline (xyz, params);

    // Candidates with their distance from the image centre: with --max-people, the most central
    // are kept (a camera looks at its subject; side walls and furniture sit at the edges).
    std::vector<std::pair<float, agex::ContourAnnotation>> candidates;
    for (std::size_t m = 0; m < result.meshes.size (); ++m)
    {
      cv::Mat mask = cv::Mat::zeros (height, width, CV_8UC1);
      Eigen::Array3f low = Eigen::Array3f::Constant (std::numeric_limits<float>::max ()), high = -low;
      for (const int index : result.meshes[m].indices)
      {
        mask.at<unsigned char> (index / width, index % width) = 255;
        const Eigen::Array3f p = result.filtered->points[index].getArray3fMap ();
        low = low.min (p);
        high = high.max (p);
      }
      // A person is as tall as a person (camera y is roughly vertical), and not a wall.
      const Eigen::Array3f extent = high - low;
      if (extent.y () < min_person_m || extent.y () > max_person_m || extent.x () > max_width_m ||
          extent.z () > max_depth_m)
        continue;
      agex::ContourAnchors anchors;
      for (const auto &p : result.interest_points)
        if (p.mesh == static_cast<int> (m) && p.rank > 1)
          anchors.extremities.emplace_back (static_cast<float> (p.u), static_cast<float> (p.v));
      const agex::ContourAnnotation annotation = agex::annotateContour (mask, anchors);
      const double fill = annotation.ok ? cv::countNonZero (mask (annotation.tight_box & cv::Rect (0, 0, width, height))) /
                                            std::max (1.0, static_cast<double> (annotation.tight_box.area ()))
                                        : 1.0;
      if (annotation.ok && fill <= max_fill)
        candidates.emplace_back (
          static_cast<float> (cv::norm ((annotation.tight_box.tl () + annotation.tight_box.br ()) * 0.5 -
                                        cv::Point (width / 2, height / 2))),
          annotation);
    }
    std::sort (candidates.begin (), candidates.end (),
               [] (const auto &a, const auto &b) { return a.first < b.first; });
    std::vector<agex::ContourAnnotation> drawn;
    agex::ImglabImage image;
    for (const auto &[depth, annotation] : candidates)
    {
      if (max_people > 0 && static_cast<int> (drawn.size ()) >= max_people)
        break;
      if (annotation.tight_box.height < common.min_height)
      {
        image.boxes.push_back ({annotation.box, "person", true, {}});
        continue;
      }
      image.boxes.push_back (annotatedBox (annotation));
      drawn.push_back (annotation);
      ++annotated;
    }
    agex::apps::writePng (staging.path (pngs[f]), colour);
    image.file = pathFromXml (common.out, pngs[f]);
    if (!common.overlay_dir.empty ())
      writeAnnotationOverlay (common.overlay_dir, pngs[f], colour, drawn, protected_files);
    std::cout << input << ": " << result.meshes.size () << " meshes, " << drawn.size () << " people annotated\n";
    dataset.images.push_back (std::move (image));
  }
  staging.commit ();
  agex::writeImglabDataset (common.out, dataset);
  std::cout << common.out << ": " << dataset.images.size () << " images, " << annotated << " people annotated\n";
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  const std::string usage = "usage: agex_annotate coco --json FILE --images DIR --out XML [options]\n"
                            "       agex_annotate rgbd INPUT... --out XML [options]\n"
                            "(agex_annotate coco --help, agex_annotate rgbd --help for the options)";
  if (argc < 2 || (std::string (argv[1]) != "coco" && std::string (argv[1]) != "rgbd"))
  {
    const bool help = argc >= 2 && (std::string (argv[1]) == "--help" || std::string (argv[1]) == "-h");
    (help ? std::cout : std::cerr) << usage << "\n";
    return help ? 0 : 1;
  }
  try
  {
    return std::string (argv[1]) == "coco" ? annotateCoco (argc - 1, argv + 1) : annotateRgbd (argc - 1, argv + 1);
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_annotate: error: " << e.what () << "\n";
    return 1;
  }
}

// agex_annotate: 180-landmark body-contour annotations without a human.
//   agex_annotate coco --json FILE --images DIR --out XML   person masks (COCO polygons)
//   agex_annotate rgbd INPUT... --out XML                     organized XYZRGBA clouds
// Writes a dlib/imglab XML dataset (square boxes, parts 000-179, shoulders when known)
// for agex_landmarks_train, agex_landmarks_eval and imglab.

#include <agex/apps/command_line.h>
#include <agex/apps/depth_pipeline.h>
#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/classification/contour_annotation.h>
#include <agex/classification/imglab_dataset.h>
#include <agex/common/atomic_file.h>
#include <agex/common/pcd_reader.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/conversions.h>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

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
                        const std::vector<agex::ContourAnnotation> &annotations)
{
  std::vector<agex::apps::LandmarkedPerson> people;
  for (const auto &a : annotations)
    people.push_back ({a.box, 1.0, a.landmarks});
  fs::create_directories (dir);
  agex::apps::writePng ((fs::path (dir) / (fs::path (name).stem ().string () + ".png")).string (),
                        agex::apps::renderLandmarkOverlay (image, people));
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
  agex::checkOutputIsNotInput (common.out, {json_path});

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
  if (!coco.contains ("images") || !coco.contains ("annotations"))
    throw std::runtime_error (json_path + ": no 'images' or 'annotations' (not a COCO file)");
  std::map<long, std::vector<const nlohmann::json *>> by_image;
  for (const auto &a : coco["annotations"])
    by_image[a.value ("image_id", -1L)].push_back (&a);

  agex::ImglabDataset dataset;
  dataset.name = common.name;
  dataset.comment = "agex_annotate coco from " + json_path;
  std::size_t annotated = 0, ignored = 0;
  for (const auto &entry : coco["images"])
  {
    const std::string file = entry.at ("file_name").get<std::string> ();
    if (!only.empty () && std::find (only.begin (), only.end (), file) == only.end ())
      continue;
    const std::string path = (fs::path (images_dir) / file).string ();
    const cv::Mat image = cv::imread (path, cv::IMREAD_COLOR);
    if (image.empty ())
      throw std::runtime_error (path + ": cannot read the image named in " + json_path);
    agex::ImglabImage out_image;
    out_image.file = pathFromXml (common.out, path);
    std::vector<agex::ContourAnnotation> drawn;
    for (const nlohmann::json *a : by_image[entry.at ("id").get<long> ()])
    {
      const auto &bbox = a->at ("bbox");
      const cv::Rect coco_box (cv::Point (static_cast<int> (bbox[0].get<double> ()), static_cast<int> (bbox[1].get<double> ())),
                               cv::Size (static_cast<int> (bbox[2].get<double> ()), static_cast<int> (bbox[3].get<double> ())));
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
      writeAnnotationOverlay (common.overlay_dir, file, image, drawn);
    dataset.images.push_back (std::move (out_image));
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
  agex::apps::PipelineParams params;
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
  agex::checkOutputIsNotInput (common.out, inputs);
  if (images_dir.empty ())
    images_dir = (fs::path (common.out).parent_path () / (fs::path (common.out).stem ().string () + "_images")).string ();
  fs::create_directories (images_dir);

  agex::ImglabDataset dataset;
  dataset.name = common.name;
  dataset.comment = "agex_annotate rgbd";
  std::size_t annotated = 0;
  for (const std::string &input : inputs)
  {
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
    const agex::apps::PipelineResult result = agex::apps::runDepthPipeline (xyz, params);

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
    const std::string png = (fs::path (images_dir) / (fs::path (input).stem ().string () + ".png")).string ();
    agex::checkOutputIsNotInput (png, inputs);
    agex::apps::writePng (png, colour);
    image.file = pathFromXml (common.out, png);
    if (!common.overlay_dir.empty ())
      writeAnnotationOverlay (common.overlay_dir, png, colour, drawn);
    std::cout << input << ": " << result.meshes.size () << " meshes, " << drawn.size () << " people annotated\n";
    dataset.images.push_back (std::move (image));
  }
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

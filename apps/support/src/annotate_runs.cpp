#include <agex/apps/annotate_runs.h>

#include <agex/apps/output_guard.h>

#include <agex/apps/command_line.h>
#include <agex/apps/landmark_annotation.h>
#include <agex/apps/output.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/landmarks/annotation_sources.h>
#include <agex/landmarks/image_files.h>
#include <agex/landmarks/imglab_dataset.h>
#include <agex/landmarks/rgbd_contour_annotator.h>

#include <boost/program_options.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <set>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
namespace
{
bool
listed (const std::vector<std::string> &names, const std::string &name)
{
  return std::find (names.begin (), names.end (), name) != names.end ();
}

// One image per input, named after it; inputs of the same name (frames/000000.pcd of two
// agex_synth runs) get a numbered suffix instead of overwriting each other.
std::vector<std::string>
rgbdImagePaths (const std::vector<std::string> &inputs, const std::string &images_dir, const InputFiles &read)
{
  std::vector<std::string> pngs;
  std::set<std::string> taken;
  for (const std::string &input : inputs)
  {
    const std::string stem = fs::path (input).stem ().string ();
    std::string name = stem + ".png";
    for (int n = 2; !taken.insert (name).second; ++n)
      name = stem + "-" + std::to_string (n) + ".png";
    pngs.push_back ((fs::path (images_dir) / name).string ());
    checkOutputPath (pngs.back (), OutputKind::Png, read);
  }
  return pngs;
}

po::options_description
rgbdSelectionOptions (RgbdPersonSelectionParams &s, std::string &images_dir)
{
  po::options_description options ("People in RGB-D frames");
  options.add_options () ("images-dir", po::value (&images_dir), "where the colour images are written (default: <out>_images)")
    ("min-person-height", po::value (&s.min_person_height)->default_value (s.min_person_height), "metres; shorter meshes are not people")
    ("max-person-height", po::value (&s.max_person_height)->default_value (s.max_person_height), "metres; taller meshes are not people")
    ("max-person-width", po::value (&s.max_person_width)->default_value (s.max_person_width), "metres; wider meshes are not people")
    ("max-person-depth", po::value (&s.max_person_depth)->default_value (s.max_person_depth), "metres; deeper meshes are not people")
    ("max-fill", po::value (&s.max_fill)->default_value (s.max_fill),
     "silhouettes filling more of their box are not people (wall strips, boxes)")
    ("max-people", po::value (&s.max_people)->default_value (s.max_people),
     "keep the N most central people per frame (0: all), e.g. 1 for agex_synth frames");
  return options;
}

// Writes the dataset and prints the closing line of who was outlined or ignored.
int
writeDataset (const AnnotateOutput &output, const ImglabDataset &dataset, const AnnotationSummary &summary)
{
  writeImglabDataset (output.out, dataset);
  std::cout << output.out << ": " << summary.line (dataset.images.size ()) << "\n";
  return 0;
}
}  // namespace

int
annotateCoco (int argc, char **argv)
{
  AnnotateOutput output;
  std::string json_path, images_dir;
  int min_keypoints = 0;
  std::vector<std::string> only;
  po::options_description options ("agex_annotate coco --json FILE --images DIR --out XML [options]\n"
                                   "Contour landmarks from COCO person masks (polygons or RLE) and keypoints");
  options.add (annotateOutputOptions (output));
  options.add_options () ("json", po::value (&json_path)->required (), "COCO annotations (polygon or RLE segmentation)")
    ("images", po::value (&images_dir)->required (), "folder with the images")
    ("min-keypoints", po::value (&min_keypoints)->default_value (min_keypoints),
     "people with fewer labelled keypoints become ignore boxes")
    ("only", po::value (&only)->multitoken (), "annotate only these image files (file_name in the JSON)");
  if (!parseCommandLine (argc, argv, options, {}))
    return 0;
  InputFiles read ({json_path});
  read.checkOutput (output.out);
  const std::vector<CocoImage> images = readCocoPeople (json_path);
  // Every image the JSON names is an input: no output may land on one.
  std::set<std::string> named;
  for (const auto &image : images)
  {
    named.insert (image.file);
    read.add ((fs::path (images_dir) / image.file).string ());
  }
  checkAnnotateOutputs (output, std::vector<std::string> (named.begin (), named.end ()), read);
  for (const std::string &file : only)
    if (!named.count (file))
      throw std::runtime_error ("--only " + file + ": no image with that file_name in " + json_path);

  ImglabDataset dataset{output.name, "agex_annotate coco from " + json_path, {}};
  AnnotationSummary summary;
  for (const auto &image : images)
  {
    if (!only.empty () && !listed (only, image.file))
      continue;
    const std::string path = (fs::path (images_dir) / image.file).string ();
    const cv::Mat pixels = readImage (path, cv::IMREAD_COLOR, "the image named in " + json_path);
    if ((image.width > 0 && image.width != pixels.cols) || (image.height > 0 && image.height != pixels.rows))
      throw std::runtime_error (path + ": the image is " + std::to_string (pixels.cols) + "x" + std::to_string (pixels.rows) +
                                ", " + json_path + " says " + std::to_string (image.width) + "x" +
                                std::to_string (image.height) + " (another image of the same name?)");
    ImglabImage entry;
    entry.file = pathFromXml (output.out, path);
    std::vector<ContourAnnotation> drawn;
    for (const CocoPerson &person : image.people)
      addPerson (annotateCocoPerson (person, pixels.size (), output.min_height, min_keypoints, json_path + ": " + image.file),
                 summary, entry, drawn);
    if (!output.overlay_dir.empty ())
      writeAnnotationOverlay (output.overlay_dir, image.file, pixels, drawn, read);
    dataset.images.push_back (std::move (entry));
  }
  return writeDataset (output, dataset, summary);
}

int
annotateMasks (int argc, char **argv)
{
  AnnotateOutput output;
  std::string images_dir, masks_dir, excluded;
  std::vector<std::string> only, skip;
  bool overlay_on_mask = false;
  MaskAnnotationOptions mask_options;
  po::options_description options ("agex_annotate masks --images DIR --masks DIR --out XML [options]\n"
                                   "Contour landmarks from mask images: each image's mask is the PNG of the same stem\n"
                                   "(or STEM_mask.png) in the masks folder, a label map of one person (0 = background)\n"
                                   "or, with --instances, an instance mask (value k = person k)");
  options.add (annotateOutputOptions (output));
  options.add_options () ("images", po::value (&images_dir)->required (), "folder with the images")
    ("masks", po::value (&masks_dir)->required (), "folder with the masks (8/16-bit grey or palette PNG)")
    ("labels-excluded", po::value (&excluded), "label-map labels that are not the person, e.g. 2,33,56 (bags)")
    ("instances", po::bool_switch (&mask_options.instances), "the masks are instance masks: value k is person k")
    ("only", po::value (&only)->multitoken (), "annotate only these image files (names in the images folder)")
    ("skip", po::value (&skip)->multitoken (), "leave these image files out (held-out test images)")
    ("overlay-on-mask", po::bool_switch (&overlay_on_mask), "draw the overlays on the mask's silhouette, not the photo");
  if (!parseCommandLine (argc, argv, options, {}))
    return 0;
  if (mask_options.instances && !excluded.empty ())
    throw std::runtime_error ("--labels-excluded applies to label maps, not to --instances");
  if (!excluded.empty ())
    mask_options.excluded_labels = parseLabelList (excluded, "--labels-excluded");
  mask_options.min_height = output.min_height;
  std::vector<std::string> without_mask;
  const auto pairs = pairImagesWithMasks (images_dir, masks_dir, without_mask);
  InputFiles read;
  std::set<std::string> names;
  for (const auto &pair : pairs)
  {
    read.add (pair.image);
    read.add (pair.mask);
    names.insert (fs::path (pair.image).filename ().string ());
  }
  checkAnnotateOutputs (output, std::vector<std::string> (names.begin (), names.end ()), read);
  for (const std::string &file : only.empty () ? skip : only)
    if (!names.count (file))
      throw std::runtime_error (file + ": no image of that name with a mask in " + images_dir);

  ImglabDataset dataset{output.name, "agex_annotate masks from " + masks_dir, {}};
  AnnotationSummary summary;
  for (const std::string &image : without_mask)
    summary.skippedImage (image, "no mask", "neither STEM.png nor STEM_mask.png in " + masks_dir);
  for (const MaskedImage &pair : pairs)
  {
    const std::string name = fs::path (pair.image).filename ().string ();
    if ((!only.empty () && !listed (only, name)) || listed (skip, name))
      continue;
    cv::Mat pixels;
    try
    {
      pixels = readImage (pair.image, cv::IMREAD_COLOR, "an image of " + images_dir);
    }
    catch (const std::runtime_error &e)
    {
      summary.skippedImage (pair.image, "unreadable image", e.what ());
      continue;
    }
    ImglabImage entry;
    entry.file = pathFromXml (output.out, pair.image);
    std::vector<ContourAnnotation> drawn;
    const MaskedImageAnnotation annotated = annotateMaskedImage (pair, pixels.size (), mask_options);
    if (!annotated.problem.empty ())
    {
      summary.skippedImage (pair.image, annotated.problem, annotated.detail);
      continue;
    }
    for (const PersonAnnotation &person : annotated.people)
      addPerson (person, summary, entry, drawn);
    if (!output.overlay_dir.empty ())
      writeAnnotationOverlay (output.overlay_dir, name,
                              overlay_on_mask ? maskSilhouette (pair.mask, mask_options.excluded_labels) : pixels, drawn,
                              read);
    dataset.images.push_back (std::move (entry));
  }
  if (dataset.images.empty ())
    throw std::runtime_error ("no image of " + images_dir + " has a usable mask in " + masks_dir);
  return writeDataset (output, dataset, summary);
}

int
annotateRgbd (int argc, char **argv)
{
  AnnotateOutput output;
  std::vector<std::string> inputs, vector_flags;
  std::string images_dir;
  RgbdPersonSelectionParams selection;
  DepthPipelineParams params;
  // People anywhere in a room, not only at the Bonn distance.
  params.crop_min = Eigen::Vector3f (-6.f, -3.f, 0.5f);
  params.crop_max = Eigen::Vector3f (6.f, 3.f, 10.f);
  po::options_description options ("agex_annotate rgbd INPUT... --out XML [options]\n"
                                   "Contour landmarks from organized XYZRGBA clouds (.pcd): the depth stages segment\n"
                                   "each person, AGEX extrema anchor the landmarks on the colour silhouette. Clouds\n"
                                   "without colour (agex_synth frames made without --colour) give a shaded depth image instead.");
  options.add (annotateOutputOptions (output)).add (rgbdSelectionOptions (selection, images_dir));
  options.add_options () ("input", po::value (&inputs)->multitoken (), "organized XYZRGBA PCD files");
  options.add (pipelineOptionsDescription (params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", -1);
  if (!parseCommandLine (argc, argv, options, positional))
    return 0;
  if (inputs.empty ())
    throw std::runtime_error ("no INPUT cloud given (see --help)");
  finishPipelineOptions (vector_flags, params);
  // The masks are drawn on the colour image's own pixels.
  if (params.working_spacing > 0.f)
    throw std::runtime_error ("--working-spacing is not for annotation: the masks are drawn at every pixel of the "
                              "colour image (leave it at 0)");
  selection.min_height_px = output.min_height;
  InputFiles read (inputs);
  read.checkOutput (output.out);
  if (images_dir.empty ())
    images_dir = (fs::path (output.out).parent_path () / (fs::path (output.out).stem ().string () + "_images")).string ();
  const std::vector<std::string> pngs = rgbdImagePaths (inputs, images_dir, read);
  // Overlays must not land on the dataset's own images either.
  InputFiles protected_files = read;
  for (const std::string &png : pngs)
    protected_files.add (png);
  checkAnnotateOutputs (output, pngs, protected_files);
  fs::create_directories (images_dir);
  // The images are staged and moved into place only once every frame has worked, so a failed
  // run leaves an earlier dataset's images as they were.
  StagingDirectory staging (images_dir);
  ImglabDataset dataset{output.name, "agex_annotate rgbd", {}};
  AnnotationSummary summary;
  for (std::size_t f = 0; f < inputs.size (); ++f)
  {
    pcl::PointCloud<pcl::PointXYZ>::Ptr xyz;
    const cv::Mat colour = readRgbdFrame (inputs[f], xyz);
    const DepthPipelineResult result = runDepthPipeline (xyz, params);
    RgbdContourAnnotator annotator;
    annotator.setInputCloud (result.filtered);
    annotator.setMeshes (result.meshes);
    annotator.setInterestPoints (result.interest_points);
    annotator.setParams (selection);
    std::vector<RgbdPerson> people;
    annotator.compute (people);
    ImglabImage image;
    std::vector<ContourAnnotation> drawn;
    const std::string too_small = "shorter than " + std::to_string (output.min_height) + " px";
    for (const RgbdPerson &person : people)
      addPerson ({inputs[f], person.too_small ? imglabIgnoreBox (person.annotation.box) : imglabBox (person.annotation),
                  person.annotation, person.too_small ? too_small : ""},
                 summary, image, drawn, false);
    writePng (staging.path (pngs[f]), colour);
    image.file = pathFromXml (output.out, pngs[f]);
    if (!output.overlay_dir.empty ())
      writeAnnotationOverlay (output.overlay_dir, pngs[f], colour, drawn, protected_files);
    std::cout << inputs[f] << ": " << result.meshes.size () << " meshes, " << drawn.size () << " people annotated\n";
    dataset.images.push_back (std::move (image));
  }
  staging.commit ();
  return writeDataset (output, dataset, summary);
}
}  // namespace apps
}  // namespace agex

#include <agex/apps/landmark_annotation.h>

#include <agex/apps/output_guard.h>

#include <agex/apps/landmarks.h>
#include <agex/apps/output.h>
#include <agex/landmarks/image_files.h>

#include <boost/program_options/value_semantic.hpp>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
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

namespace
{
std::string
overlayPath (const std::string &dir, const std::string &name)
{
  return (fs::path (dir) / (fs::path (name).stem ().string () + ".png")).string ();
}
}  // namespace

void
checkAnnotateOutputs (const AnnotateOutput &output, const std::vector<std::string> &image_names, const InputFiles &inputs)
{
  checkOutputPath (output.out, OutputKind::ImglabXml, inputs);
  if (output.overlay_dir.empty ())
    return;
  std::vector<std::string> overlays;
  for (const std::string &name : image_names)
    overlays.push_back (overlayPath (output.overlay_dir, name));
  checkPngsInFolder (overlays, inputs);
}

void
writeAnnotationOverlay (const std::string &dir, const std::string &name, const cv::Mat &image,
                        const std::vector<ContourAnnotation> &annotations, const InputFiles &inputs)
{
  std::vector<LandmarkedPerson> people;
  for (const auto &a : annotations)
    people.push_back ({a.box, 1.0, a.landmarks});
  const std::string path = overlayPath (dir, name);
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

void
addPerson (const PersonAnnotation &person, AnnotationSummary &summary, ImglabImage &entry,
           std::vector<ContourAnnotation> &drawn, bool print)
{
  if (person.box.ignore)
    summary.ignored (person.who, person.ignore_reason, print);
  else
  {
    drawn.push_back (person.annotation);
    summary.outlined ();
  }
  entry.boxes.push_back (person.box);
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

#pragma once
// What agex_annotate's subcommands share around the library's annotation sources
// (agex/landmarks/annotation_sources.h): the output flags, image paths as the XML writes them,
// overlays, a summary of who was outlined or ignored and why, and a staging folder for the
// images it writes.

#include <agex/io/atomic_file.h>
#include <agex/landmarks/annotation_sources.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/imglab_dataset.h>

#include <boost/program_options/options_description.hpp>
#include <opencv2/core.hpp>

#include <map>
#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** The output flags every subcommand has. */
struct AnnotateOutput
{
  std::string out, overlay_dir, name;
  int min_height = 48;
};
boost::program_options::options_description annotateOutputOptions (AnnotateOutput &output);

/** An image path as written into the XML: relative to the XML's folder when it can be. */
std::string pathFromXml (const std::string &xml_path, const std::string &image_path);

/** \brief Refuses the outputs of a run before it reads any image: --out unless it is free,
  * empty or an imglab dataset agex_annotate wrote, and each overlay <dir>/<stem>.png of the
  * named images unless it is free or an earlier agex PNG; none may land on an input.
  * \throws std::runtime_error naming the path */
void checkAnnotateOutputs (const AnnotateOutput &output, const std::vector<std::string> &image_names,
                           const InputFiles &inputs);

/** Writes <dir>/<stem of name>.png with the annotations drawn (never onto an input). */
void writeAnnotationOverlay (const std::string &dir, const std::string &name, const cv::Mat &image,
                             const std::vector<ContourAnnotation> &annotations, const InputFiles &inputs);

/** People outlined and ignored, images left out, each with its reason, for the closing line. */
class AnnotationSummary
{
public:
  void outlined () { ++outlined_; }
  /** A person that became an ignore box; the reason is printed with where (file, person). */
  void ignored (const std::string &where, const std::string &reason, bool print = true);
  /** An image that is not in the dataset at all (no usable mask). Printed with detail;
    * counted by reason. */
  void skippedImage (const std::string &file, const std::string &reason, const std::string &detail = "");
  std::size_t outlinedCount () const { return outlined_; }
  /** "N images, P people outlined, I ignore boxes (why: count; ...), S images left out (...)" */
  std::string line (std::size_t images) const;

private:
  std::size_t outlined_ = 0, ignored_ = 0, skipped_ = 0;
  std::map<std::string, std::size_t> ignore_reasons_, skip_reasons_;
};

/** \brief A person into the dataset's entry: counted in summary (an ignore box's reason
  * printed with its who when print), its box added to entry, an outline to drawn. */
void addPerson (const PersonAnnotation &person, AnnotationSummary &summary, ImglabImage &entry,
                std::vector<ContourAnnotation> &drawn, bool print = true);

/** The mask file as a grey silhouette (labelled pixels light, excluded labels mid grey,
  * background dark), for overlays that show annotations without the photos. */
cv::Mat maskSilhouette (const std::string &mask_path, const std::vector<int> &excluded_labels);

/** Labels from "2,33,56". \throws std::runtime_error naming flag on anything else */
std::vector<int> parseLabelList (const std::string &text, const std::string &flag);

/** Files written into a hidden folder inside their destination and renamed into it on
  * commit (); destroyed uncommitted, the folder and what it holds are removed. */
class StagingDirectory
{
public:
  explicit StagingDirectory (const std::string &destination);
  ~StagingDirectory ();
  StagingDirectory (const StagingDirectory &) = delete;
  StagingDirectory &operator= (const StagingDirectory &) = delete;
  /** Where to write the file that will end up at final_path (inside the destination). */
  std::string path (const std::string &final_path);
  void commit ();

private:
  std::string dir_;
  std::vector<std::string> staged_;
};
}  // namespace apps
}  // namespace agex

#pragma once
// What agex_annotate's subcommands share: the output flags, the imglab boxes, overlays, a
// summary of who was outlined or ignored and why, and the readers of the annotation sources
// (COCO JSON, mask folders, RGB-D clouds).

#include <agex/io/atomic_file.h>
#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/imglab_dataset.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <boost/program_options/options_description.hpp>
#include <nlohmann/json.hpp>
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

/** The imglab box of an annotated person: square box, parts 000-179. */
ImglabBox annotatedBox (const ContourAnnotation &annotation);
/** An ignore box (label "person") over box made square. */
ImglabBox ignoreBox (const cv::Rect &box);

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

// ---- COCO

/** A person annotation of a COCO file. */
struct CocoPerson
{
  long id = -1;
  cv::Rect bbox;
  bool crowd = false;
  int num_keypoints = 0;
  std::vector<cv::Point3f> keypoints;  ///< (x, y, visibility), 17 when given
  nlohmann::json segmentation;         ///< polygons, an RLE object, or null
};

struct CocoImage
{
  long id = -1;
  std::string file;
  int width = 0, height = 0;  ///< as the JSON says (0: not given)
  std::vector<CocoPerson> people;
};

/** \brief The images and person annotations of a COCO file (only the category named
  * "person" when the file lists categories). \throws std::runtime_error naming the file and
  * the entry (image or annotation id) at fault */
std::vector<CocoImage> readCocoPeople (const std::string &json_path);

/** \brief The mask of a COCO person: its polygons filled, or its RLE (compressed string or
  * list of counts) decoded. Empty when the person has no segmentation.
  * \throws std::runtime_error (where + the problem) for a malformed segmentation or an RLE of
  * another size than the image */
cv::Mat cocoPersonMask (const CocoPerson &person, const cv::Size &image_size, const std::string &where);

// ---- Mask folders

/** An image and the mask file that goes with it. */
struct MaskedImage
{
  std::string image, mask;
};

/** \brief The images of images_dir (sorted by name) paired with the mask of the same stem in
  * masks_dir: STEM.png or, as in Penn-Fudan, STEM_mask.png. Images without one are listed in
  * without_mask. \throws std::runtime_error when a folder cannot be read */
std::vector<MaskedImage> pairImagesWithMasks (const std::string &images_dir, const std::string &masks_dir,
                                              std::vector<std::string> &without_mask);

/** \brief A label or instance mask: 8 or 16-bit grey, or a palette PNG (its indices, as in
  * Penn-Fudan's PedMasks; OpenCV alone would give the palette's colours).
  * \throws std::runtime_error naming the file: unreadable, or a colour image */
cv::Mat readLabelImage (const std::string &path);

/** What decides who is outlined in a mask. */
struct MaskAnnotationOptions
{
  std::vector<int> excluded_labels;  ///< label maps: labels that are not the person (bags)
  bool instances = false;            ///< value k is person k (else a label map of one person)
  int min_height = 48;               ///< shorter people become ignore boxes
  ContourAnnotationParams contour;
};

/** The mask file as a grey silhouette (labelled pixels light, excluded labels mid grey,
  * background dark), for overlays that show annotations without the photos. */
cv::Mat maskSilhouette (const std::string &mask_path, const std::vector<int> &excluded_labels);

/** Labels from "2,33,56". \throws std::runtime_error naming flag on anything else */
std::vector<int> parseLabelList (const std::string &text, const std::string &flag);

/** \brief Outlines the people of one image's mask into out (annotated and ignore boxes, each
  * ignore box's reason printed and counted in summary) and drawn (for overlays). Returns false,
  * with the reason in summary, when the image is left out: an unreadable mask, one of another
  * size than the image, or an empty one (a person whose mask is missing must not become
  * background either). */
bool annotateMaskedImage (const MaskedImage &pair, const cv::Size &image_size, const MaskAnnotationOptions &options,
                          AnnotationSummary &summary, ImglabImage &out, std::vector<ContourAnnotation> &drawn);

/** \brief One COCO person into out: annotated, or an ignore box with its reason (crowd,
  * no segmentation, shorter than min_height, fewer than min_keypoints keypoints, no outline).
  * \throws std::runtime_error for a malformed segmentation (cocoPersonMask) */
void annotateCocoPerson (const CocoPerson &person, const cv::Size &image_size, int min_height, int min_keypoints,
                         const std::string &where, AnnotationSummary &summary, ImglabImage &out,
                         std::vector<ContourAnnotation> &drawn);

// ---- RGB-D clouds

/** \brief The colour image of an organized XYZRGBA PCD file and its XYZ cloud. Clouds without
  * colour give shaded depth (near bright). \throws std::runtime_error (FrameError) naming the
  * file when it cannot be read or is not organized */
cv::Mat readRgbdFrame (const std::string &path, pcl::PointCloud<pcl::PointXYZ>::Ptr &xyz);

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

#pragma once
// The annotation sources agex_annotate outlines people from, read into imglab boxes: COCO
// files (person polygons or RLE masks, keypoints as anchor hints) and folders of mask images
// (label maps of one person, or instance masks). Every person becomes an outlined box (parts
// 000-179, and the shoulders when known) or an ignore box with its reason: a person left out
// altogether would teach the detector that people are background. (RGB-D frames:
// rgbd_contour_annotator.h.)

#include <agex/landmarks/contour_annotation.h>
#include <agex/landmarks/imglab_dataset.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace agex
{
/** The imglab box of an outlined person: its square box, parts 000-179. */
ImglabBox imglabBox (const ContourAnnotation &annotation);
/** An ignore box (label "person") over box made square. */
ImglabBox imglabIgnoreBox (const cv::Rect &box);

/** One person of an annotation source, as it goes into the dataset. */
struct PersonAnnotation
{
  std::string who;               ///< where the person came from (file, person), for reports
  ImglabBox box;                 ///< outlined (box.ignore false) or an ignore box
  ContourAnnotation annotation;  ///< the outline, ok when box is not an ignore box
  std::string ignore_reason;     ///< why box is an ignore box
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

/** \brief One COCO person of an image (where: its file), who = "<where>: person <id>":
  * outlined from its mask with its keypoints as anchor hints (and its shoulders, COCO keypoints
  * 5 and 6, kept as parts), or an ignore box over COCO's box, with the reason: crowd, shorter
  * than min_height, fewer than min_keypoints keypoints, no segmentation, no outline.
  * \throws std::runtime_error for a malformed segmentation (cocoPersonMask) */
PersonAnnotation annotateCocoPerson (const CocoPerson &person, const cv::Size &image_size, int min_height,
                                     int min_keypoints, const std::string &where);

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

/** What decides who is outlined in a mask. */
struct MaskAnnotationOptions
{
  std::vector<int> excluded_labels;  ///< label maps: labels that are not the person (bags)
  bool instances = false;            ///< value k is person k (else a label map of one person)
  int min_height = 48;               ///< shorter people become ignore boxes
  ContourAnnotationParams contour;
};

/** The people of one image's mask, or why the image is left out. */
struct MaskedImageAnnotation
{
  std::string problem;  ///< not empty: the image is left out, for this reason...
  std::string detail;   ///< ...and this detail (the mask file, its size)
  std::vector<PersonAnnotation> people;  ///< in the order of the mask's people
};

/** \brief Outlines the people of one image's mask (readLabelImage): the person of a label map,
  * or each person of an instance mask (who: the image, and ": person k"). The image is left out
  * (problem set, no people) for an unreadable mask, one of another size than the image, or an
  * empty one: a person whose mask is missing must not become background either. */
MaskedImageAnnotation annotateMaskedImage (const MaskedImage &pair, const cv::Size &image_size,
                                           const MaskAnnotationOptions &options);
}  // namespace agex

#pragma once
// Automatic 180-landmark body-contour annotation from a person mask.
//
// The outer contour of the mask is walked counter-clockwise on screen from the top of the
// head. Five anchors split it into segments: top of head (landmark 0), the screen-left hand
// (36), the screen-left foot (72), the screen-right foot (108) and the screen-right hand
// (144). Each segment holds 36 landmarks spread evenly by arc length, so a landmark index
// means the same body place in every image. Anchors come from keypoints (COCO), from
// unlabelled extremities (AGEX on depth) or, where missing, from the contour's shape.
// Mirroring an image left-right maps landmark i to landmark (180 - i) mod 180.
// The rules for anchors without hints are those of ContourAnnotationParams (doc/landmarks.md).

#include <opencv2/core.hpp>

#include <array>
#include <limits>
#include <string>
#include <vector>

namespace agex
{
constexpr int kContourLandmarkCount = 180;
constexpr int kContourAnchorCount = 5;
constexpr int kLandmarksPerSegment = kContourLandmarkCount / kContourAnchorCount;

/** Part name of landmark i in imglab files: "000" ... "179" (sorted = numeric order). */
std::string contourLandmarkName (int index);
/** Landmark index of a part name, -1 when the name is not a landmark. */
int contourLandmarkIndex (const std::string &name);
/** The landmark that landmark i becomes when the image is mirrored left-right. */
int mirroredContourLandmark (int index);

/** Hints for the anchors, image pixels. NaN coordinates mean unknown. */
struct ContourAnchors
{
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN ();
  cv::Point2f head{kUnknown, kUnknown};  ///< a point on or near the head (nose, eyes)
  std::vector<cv::Point2f> hands;        ///< up to 2, any order, near the hand tips
  std::vector<cv::Point2f> feet;         ///< up to 2, any order
  /** Unlabelled body extremities (e.g. AGEX points): labelled head / feet / hands by
    * position and used where the labelled hints above are missing. */
  std::vector<cv::Point2f> extremities;
  cv::Point2f up{0.f, -1.f};  ///< the body's up direction in the image
};

struct ContourAnnotationParams
{
  /** Morphological closing (pixels) that joins mask pieces split by occluders; negative:
    * 2% of the mask's height. */
  int closing_px = -1;
  /** Masks with fewer pixels are rejected. */
  int min_area_px = 100;
  /** How far hand hints may lie from the contour before they are ignored, as a fraction
    * of the body's height (a wrist hidden behind the body says nothing about the outline). */
  float max_hint_distance = 0.12f;
  // Anchors from the shape alone (no hint), in body heights (the outline's extent along up):
  /** The head top is the highest outline point at most this far sideways from the body's
    * centre line (through the centre of its area): a raised hand is higher, but off to the side. */
  float head_band = 0.12f;
  /** A hand is the outline's farthest point sideways above the hips when that lies farther
    * than this from the centre line (an arm held out; arm span is about one body height)... */
  float hand_spread = 0.25f;
  /** ...else the first outline point this far below the top, going from the head top down
    * the hand's side: the outer side of a hanging arm at the wrist's height (about 0.52 of the
    * stature below the head for an upright adult), or the coat's edge there. */
  float wrist_drop = 0.52f;
};

struct ContourAnnotation
{
  bool ok = false;
  std::string problem;                    ///< why not ok
  std::vector<cv::Point2f> landmarks;     ///< kContourLandmarkCount points when ok
  std::vector<cv::Point> contour;         ///< the outline, counter-clockwise from the head top
  std::array<int, kContourAnchorCount> anchor_contour_index{};  ///< anchors on contour
  std::array<bool, kContourAnchorCount> anchor_from_hint{};     ///< false: found from the shape
  bool anchors_reordered = false;  ///< hints out of contour order were sorted
  cv::Rect tight_box;              ///< bounding box of the outline
  cv::Rect box;                    ///< square box (side = the larger of width and height), same centre
};

/** Annotates one person mask (CV_8U, non-zero = person). */
ContourAnnotation annotateContour (const cv::Mat &mask, const ContourAnchors &anchors,
                                   const ContourAnnotationParams &params = ContourAnnotationParams ());

/** Anchor hints from the 17 COCO keypoints (x, y, visibility; visibility 0 = absent). */
ContourAnchors anchorsFromCocoKeypoints (const std::vector<cv::Point3f> &keypoints);

/** A person mask from COCO polygons ({x0, y0, x1, y1, ...} each), filled. */
cv::Mat maskFromPolygons (const cv::Size &size, const std::vector<std::vector<float>> &polygons);

/** The square box (side = max(width, height)) with the same centre. */
cv::Rect squareBox (const cv::Rect &box);

/** Mean distance of points to the closed polyline through outline. */
double meanDistanceToClosedPolyline (const std::vector<cv::Point2f> &points,
                                     const std::vector<cv::Point2f> &outline);
}  // namespace agex

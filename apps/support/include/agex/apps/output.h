#pragma once
// What the apps write: JSON documents and overlay PNGs, always atomically (and PNGs marked
// as agex's, see output_guard.h).

#include <agex/classification/body_part_label_point.h>
#include <agex/classification/part_modes.h>
#include <agex/common/point_types.h>
#include <agex/detection/body_part_detection.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/filters/person_segmentation.h>
#include <agex/io/dataset.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** Writes a JSON document atomically (pretty-printed, trailing newline). */
void writeJson (const std::string &path, const nlohmann::json &doc);

/** Encodes and writes a PNG atomically. \throws std::runtime_error on failure */
void writePng (const std::string &path, const cv::Mat &image);

/** An interest point as the apps' JSON shows it. */
nlohmann::json interestPointJson (const agex::InterestPoint &p);

/** agex_keypoints' document of a frame (named frame): its size, the points of each mesh, the
  * interest points and each stage's milliseconds. */
nlohmann::json keypointsJson (const std::string &frame, const pcl::PointCloud<pcl::PointXYZ> &cloud,
                              const DepthPipelineResult &result);

/** \brief Draws the depth frame (grey, near = bright), the kept meshes tinted,
  * and each interest point as a disc coloured by rank with an orientation arrow. */
cv::Mat renderOverlay (const pcl::PointCloud<pcl::PointXYZ> &frame,
                       const std::vector<pcl::PointIndices> &meshes,
                       const pcl::PointCloud<agex::InterestPoint> &points);

/** Colour (BGR) for a 1-based rank, shared by the overlay and its legend. */
cv::Scalar rankColour (int rank);

/** A line plot: named series of (x, y) points on fixed axes. */
struct Plot
{
  struct Series
  {
    std::string name;
    cv::Scalar colour;
    std::vector<cv::Point2d> points;
  };
  std::string title, x_label, y_label;
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;
  double x_tick = 0.1, y_tick = 0.1;
  std::vector<Series> series;
};

/** Renders a plot (white background, grid, axes with tick labels, legend) as BGR. */
cv::Mat renderPlot (const Plot &plot, int width = 720, int height = 480);

/** Colour (BGR) of a body-part class in plots: head red, hand green, foot blue. */
cv::Scalar bodyPartColour (int part);

/** \brief The overlay of agex_detect: the frame and its meshes as renderOverlay draws them,
  * and each detection at or above min_confidence circled in its class colour with its
  * confidence and orientation arrow (the most confident drawn last). */
cv::Mat renderDetections (const pcl::PointCloud<pcl::PointXYZ> &frame, const std::vector<pcl::PointIndices> &meshes,
                          const std::vector<BodyPartDetection> &detections, float min_confidence);
/** \brief The part map of a frame: depth grey (near bright) with the part labels blended over
  * the labelled pixels (head red, hand green, foot blue, other body yellow, a labelled pixel
  * of no part magenta), the labelled tips (truth, may be empty) as white circles and the tips
  * of part modes of confidence >= 0.3 as crosses in their part's colour. Frames under 480
  * rows are enlarged by a whole factor. */
cv::Mat renderPartLabels (const pcl::PointCloud<pcl::PointXYZ> &frame, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                          const std::vector<PartMode> &modes, const std::vector<PartLabel> &truth);
/** The people of a frame as agex_detect writes them: per person its id (its index),
  * pixels, distance (median depth, m), height (top above the floor, m), too_far (too
  * few pixels for a hand: no hand guesses) and hidden (seen only in pieces behind a
  * nearer person). */
nlohmann::json personsJson (const std::vector<PersonInfo> &persons);
}  // namespace apps
}  // namespace agex

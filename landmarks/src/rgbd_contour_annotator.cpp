#include <agex/landmarks/rgbd_contour_annotator.h>

#include <agex/io/pcd_reader.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace agex
{
std::string
RgbdContourAnnotator::sizeProblem (const pcl::PointIndices &mesh) const
{
  Eigen::Array3f low = Eigen::Array3f::Constant (std::numeric_limits<float>::max ()), high = -low;
  for (const int index : mesh.indices)
  {
    const Eigen::Array3f p = cloud_->points[index].getArray3fMap ();
    low = low.min (p);
    high = high.max (p);
  }
  const Eigen::Array3f extent = high - low;
  if (extent.y () < params_.min_person_height)
    return "shorter than a person";
  if (extent.y () > params_.max_person_height)
    return "taller than a person";
  if (extent.x () > params_.max_person_width)
    return "wider than a person";
  if (extent.z () > params_.max_person_depth)
    return "deeper than a person";
  return "";
}

cv::Mat
RgbdContourAnnotator::meshMask (const pcl::PointIndices &mesh) const
{
  const int width = static_cast<int> (cloud_->width);
  cv::Mat mask = cv::Mat::zeros (static_cast<int> (cloud_->height), width, CV_8UC1);
  for (const int index : mesh.indices)
    mask.at<unsigned char> (index / width, index % width) = 255;
  return mask;
}

ContourAnchors
RgbdContourAnnotator::meshAnchors (int mesh) const
{
  // AGEX_1 is the mesh's geodesic centroid (on the torso); the later points are its extremities.
  ContourAnchors anchors;
  for (const auto &p : points_)
    if (p.mesh == mesh && p.rank > 1)
      anchors.extremities.emplace_back (static_cast<float> (p.u), static_cast<float> (p.v));
  return anchors;
}

double
RgbdContourAnnotator::silhouetteFill (const cv::Mat &mask, const cv::Rect &box)
{
  return cv::countNonZero (mask (box & cv::Rect (0, 0, mask.cols, mask.rows))) /
         std::max (1.0, static_cast<double> (box.area ()));
}

void
RgbdContourAnnotator::compute (std::vector<RgbdPerson> &people)
{
  people.clear ();
  rejections_.clear ();
  if (!cloud_ || cloud_->height < 2 || cloud_->points.size () != static_cast<std::size_t> (cloud_->width) * cloud_->height)
  {
    PCL_ERROR ("[agex::RgbdContourAnnotator::compute] the input cloud must be organized\n");
    return;
  }
  const cv::Point centre (static_cast<int> (cloud_->width) / 2, static_cast<int> (cloud_->height) / 2);
  std::vector<RgbdPerson> candidates;
  for (std::size_t m = 0; m < meshes_.size (); ++m)
  {
    const int mesh = static_cast<int> (m);
    for (const int index : meshes_[m].indices)
      if (index < 0 || static_cast<std::size_t> (index) >= cloud_->points.size ())
      {
        PCL_ERROR ("[agex::RgbdContourAnnotator::compute] mesh %d indexes outside the cloud\n", mesh);
        people.clear ();
        return;
      }
    if (const std::string problem = sizeProblem (meshes_[m]); !problem.empty ())
    {
      rejections_.push_back ({mesh, problem});
      continue;
    }
    const cv::Mat mask = meshMask (meshes_[m]);
    RgbdPerson person;
    person.mesh = mesh;
    person.annotation = annotateContour (mask, meshAnchors (mesh), params_.contour);
    if (!person.annotation.ok)
    {
      rejections_.push_back ({mesh, "no outline: " + person.annotation.problem});
      continue;
    }
    if (silhouetteFill (mask, person.annotation.tight_box) > params_.max_fill)
    {
      rejections_.push_back ({mesh, "fills its box like a wall or a box, not a person"});
      continue;
    }
    const cv::Rect &box = person.annotation.tight_box;
    person.centre_distance_px = static_cast<float> (cv::norm ((box.tl () + box.br ()) * 0.5 - centre));
    candidates.push_back (std::move (person));
  }
  std::stable_sort (candidates.begin (), candidates.end (), [] (const RgbdPerson &a, const RgbdPerson &b) {
    return a.centre_distance_px < b.centre_distance_px;
  });
  int annotated = 0;
  for (RgbdPerson &person : candidates)
  {
    if (params_.max_people > 0 && annotated >= params_.max_people)
    {
      rejections_.push_back ({person.mesh, "beyond the " + std::to_string (params_.max_people) + " most central people"});
      continue;
    }
    person.too_small = person.annotation.tight_box.height < params_.min_height_px;
    annotated += !person.too_small;
    people.push_back (std::move (person));
  }
}

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
}  // namespace agex

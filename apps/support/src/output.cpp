#include <agex/apps/output.h>

#include <agex/common/atomic_file.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace agex
{
namespace apps
{
void
writeJson (const std::string &path, const nlohmann::json &doc)
{
  writeFileAtomic (path, doc.dump (2) + "\n");
}

void
writePng (const std::string &path, const cv::Mat &image)
{
  std::vector<unsigned char> bytes;
  if (!cv::imencode (".png", image, bytes))
    throw std::runtime_error (path + ": PNG encoding failed");
  writeFileAtomic (path, std::string (bytes.begin (), bytes.end ()));
}

nlohmann::json
interestPointJson (const agex::InterestPoint &p)
{
  return {{"x", p.x},
          {"y", p.y},
          {"z", p.z},
          {"orientation", {p.orientation[0], p.orientation[1], p.orientation[2]}},
          {"rank", p.rank},
          {"mesh", p.mesh},
          {"u", p.u},
          {"v", p.v},
          {"geodesic_distance", p.geodesic_distance}};
}

cv::Scalar
rankColour (int rank)
{
  // A fixed, easily told apart palette; ranks past its end reuse the last colour.
  static const cv::Scalar palette[] = {
      {255, 255, 255}, {0, 0, 255},   {0, 165, 255}, {0, 255, 255}, {0, 255, 0},
      {255, 255, 0},   {255, 0, 0},   {255, 0, 255}, {128, 128, 255}, {128, 255, 128}};
  const int n = static_cast<int> (sizeof (palette) / sizeof (palette[0]));
  return palette[std::clamp (rank - 1, 0, n - 1)];
}

cv::Mat
renderOverlay (const pcl::PointCloud<pcl::PointXYZ> &frame, const std::vector<pcl::PointIndices> &meshes,
               const pcl::PointCloud<agex::InterestPoint> &points)
{
  const int width = static_cast<int> (frame.width), height = static_cast<int> (std::max (1u, frame.height));
  // Grey depth, near bright, scaled to the frame's own range.
  float zmin = std::numeric_limits<float>::max (), zmax = 0.f;
  for (const auto &p : frame.points)
    if (std::isfinite (p.z))
    {
      zmin = std::min (zmin, p.z);
      zmax = std::max (zmax, p.z);
    }
  cv::Mat image (height, width, CV_8UC3, cv::Scalar (0, 0, 0));
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const float z = frame.points[static_cast<std::size_t> (v) * width + u].z;
      if (!std::isfinite (z))
        continue;
      const float t = zmax > zmin ? (z - zmin) / (zmax - zmin) : 0.f;
      const auto g = static_cast<unsigned char> (60 + 150 * (1.f - t));
      image.at<cv::Vec3b> (v, u) = cv::Vec3b (g, g, g);
    }
  // Meshes tinted, alternating hues so that neighbours stay apart.
  static const cv::Vec3b tints[] = {{80, 200, 80}, {200, 120, 60}, {60, 120, 200}, {200, 80, 200}};
  for (std::size_t m = 0; m < meshes.size (); ++m)
    for (const auto i : meshes[m].indices)
    {
      cv::Vec3b &px = image.at<cv::Vec3b> (i / width, i % width);
      const cv::Vec3b tint = tints[m % 4];
      for (int c = 0; c < 3; ++c)
        px[c] = static_cast<unsigned char> ((px[c] + tint[c]) / 2);
    }
  // Small frames (the 144x176 view) are scaled up so that markers stay legible.
  const int scale = std::max (1, 480 / std::max (1, height));
  if (scale > 1)
    cv::resize (image, image, cv::Size (), scale, scale, cv::INTER_NEAREST);
  const int radius = 6, arrow = 40;
  for (const auto &p : points)
  {
    const cv::Point centre ((p.u + 0.5) * scale, (p.v + 0.5) * scale);
    const cv::Scalar colour = rankColour (p.rank);
    // Image x and y follow the camera's x and y, so the orientation's xy part,
    // drawn to scale, shows where the limb points in the picture.
    const cv::Point tip = centre + cv::Point (static_cast<int> (std::lround (p.orientation[0] * arrow)),
                                              static_cast<int> (std::lround (p.orientation[1] * arrow)));
    if (tip != centre)
      cv::arrowedLine (image, centre, tip, colour, 2, cv::LINE_AA, 0, 0.3);
    cv::circle (image, centre, radius, colour, cv::FILLED, cv::LINE_AA);
    cv::circle (image, centre, radius, cv::Scalar (0, 0, 0), 1, cv::LINE_AA);
    cv::putText (image, std::to_string (p.rank), centre + cv::Point (radius + 2, -radius),
                 cv::FONT_HERSHEY_SIMPLEX, 0.5, colour, 1, cv::LINE_AA);
  }
  return image;
}
}  // namespace apps
}  // namespace agex

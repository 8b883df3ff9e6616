#include <agex/apps/output.h>

#include <agex/apps/output_guard.h>
#include <agex/io/atomic_file.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
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
  // Marked, so that a later run can tell its own output from any other PNG (output_guard.h).
  writeFileAtomic (path, markAgexPng (std::string (bytes.begin (), bytes.end ())));
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

nlohmann::json
keypointsJson (const std::string &frame, const pcl::PointCloud<pcl::PointXYZ> &cloud, const DepthPipelineResult &result)
{
  nlohmann::json doc;
  doc["frame"] = frame;
  doc["width"] = cloud.width;
  doc["height"] = cloud.height;
  doc["meshes"] = result.meshes.size ();
  doc["mesh_points"] = nlohmann::json::array ();
  for (const auto &mesh : result.meshes)
    doc["mesh_points"].push_back (mesh.indices.size ());
  // Mesh points count working pixels (DepthPipelineParams::working_spacing); u and v are the input's.
  doc["working_stride"] = result.stride;
  doc["interest_points"] = nlohmann::json::array ();
  for (const auto &p : result.interest_points)
  {
    nlohmann::json point = interestPointJson (p);
    if (result.stride > 1 && result.filtered)
    {
      const Eigen::Vector2i pixel = result.inputPixel (p.v * static_cast<int> (result.filtered->width) + p.u);
      point["u"] = pixel.x ();
      point["v"] = pixel.y ();
    }
    doc["interest_points"].push_back (point);
  }
  doc["ms"] = nlohmann::json::object ();
  for (const auto &[stage, ms] : result.ms)
    doc["ms"][stage] = ms;
  return doc;
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
  // Both sides count, so that a wide, short frame is not blown up past 4096 pixels.
  const int scale = std::max (1, std::min (480 / std::max (1, height), 4096 / std::max (1, image.cols)));
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
cv::Scalar
bodyPartColour (int part)
{
  static const cv::Scalar colours[] = {{40, 40, 220}, {40, 170, 40}, {220, 110, 30}};
  return colours[std::clamp (part, 0, 2)];
}

cv::Mat
renderDetections (const pcl::PointCloud<pcl::PointXYZ> &frame, const std::vector<pcl::PointIndices> &meshes,
                  const std::vector<BodyPartDetection> &detections, float min_confidence)
{
  cv::Mat image = renderOverlay (frame, meshes, pcl::PointCloud<InterestPoint> ());
  const int scale = std::max (1, image.rows / static_cast<int> (std::max (1u, frame.height)));
  for (auto it = detections.rbegin (); it != detections.rend (); ++it)  // most confident drawn last
  {
    if (it->confidence < min_confidence)
      continue;
    const cv::Point centre ((it->u + 0.5) * scale, (it->v + 0.5) * scale);
    const cv::Scalar colour = bodyPartColour (static_cast<int> (it->part));
    const cv::Point tip = centre + cv::Point (static_cast<int> (std::lround (it->orientation.x () * 40)),
                                              static_cast<int> (std::lround (it->orientation.y () * 40)));
    if (tip != centre)
      cv::arrowedLine (image, centre, tip, colour, 2, cv::LINE_AA, 0, 0.3);
    cv::circle (image, centre, 9, colour, 3, cv::LINE_AA);
    char text[64];
    std::snprintf (text, sizeof text, "%s %.2f", bodyPartName (it->part), it->confidence);
    cv::putText (image, text, centre + cv::Point (12, -8), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar (0, 0, 0), 3,
                 cv::LINE_AA);
    cv::putText (image, text, centre + cv::Point (12, -8), cv::FONT_HERSHEY_SIMPLEX, 0.55, colour, 1, cv::LINE_AA);
  }
  return image;
}

namespace
{
cv::Vec3b
partColour (int part)
{
  switch (part)
  {
  case kLabelHead: return {60, 60, 230};        // red (BGR)
  case kLabelHand: return {60, 220, 60};        // green
  case kLabelFoot: return {230, 120, 40};       // blue
  case kLabelOtherBody: return {40, 200, 230};  // yellow
  default: return {160, 60, 160};               // magenta: a labelled pixel of no part
  }
}
}  // namespace

cv::Mat
renderPartLabels (const pcl::PointCloud<pcl::PointXYZ> &frame, const pcl::PointCloud<BodyPartLabelPoint> &labels,
                  const std::vector<PartMode> &modes, const std::vector<PartLabel> &truth)
{
  const int width = static_cast<int> (frame.width), height = static_cast<int> (frame.height);
  float zmin = std::numeric_limits<float>::max (), zmax = 0.f;
  for (const auto &p : frame.points)
    if (std::isfinite (p.z))
      zmin = std::min (zmin, p.z), zmax = std::max (zmax, p.z);
  cv::Mat image (height, width, CV_8UC3, cv::Scalar (0, 0, 0));
  const bool same_grid = labels.width == frame.width && labels.height == frame.height;
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u)
    {
      const float z = frame (u, v).z;
      if (std::isfinite (z))
      {
        const float t = zmax > zmin ? (z - zmin) / (zmax - zmin) : 0.f;
        const auto g = static_cast<unsigned char> (50 + 140 * (1.f - t));
        image.at<cv::Vec3b> (v, u) = cv::Vec3b (g, g, g);
      }
      if (!same_grid)
        continue;
      const auto &q = labels (u, v);
      if (!std::isfinite (q.z) || q.label == kLabelNone)
        continue;
      const cv::Vec3b c = partColour (q.label);
      cv::Vec3b &px = image.at<cv::Vec3b> (v, u);
      for (int k = 0; k < 3; ++k)
        px[k] = static_cast<unsigned char> ((px[k] + 3 * c[k]) / 4);
    }
  const int scale = std::max (1, 480 / std::max (1, height));
  if (scale > 1)
    cv::resize (image, image, cv::Size (), scale, scale, cv::INTER_NEAREST);
  auto pixel = [scale] (float u, float v) {
    return cv::Point (static_cast<int> ((u + 0.5f) * scale), static_cast<int> ((v + 0.5f) * scale));
  };
  for (const auto &l : truth)
    if (l.visible && l.tip_px.allFinite ())
      cv::circle (image, pixel (l.tip_px.x (), l.tip_px.y ()), 7, cv::Scalar (255, 255, 255), 1, cv::LINE_AA);
  for (const auto &m : modes)
  {
    if (m.confidence < 0.3f || m.tip_index < 0 || width <= 0)
      continue;
    const cv::Point p = pixel (static_cast<float> (m.tip_index % width), static_cast<float> (m.tip_index / width));
    const cv::Vec3b c = partColour (m.part);
    cv::drawMarker (image, p, cv::Scalar (c[0], c[1], c[2]), cv::MARKER_CROSS, 14, 2);
    cv::drawMarker (image, p, cv::Scalar (0, 0, 0), cv::MARKER_CROSS, 14, 1);
  }
  return image;
}

cv::Mat
renderPlot (const Plot &plot, int width, int height)
{
  cv::Mat image (height, width, CV_8UC3, cv::Scalar (255, 255, 255));
  const int left = 70, right = 20, top = 40, bottom = 60;
  const double sx = (width - left - right) / (plot.x_max - plot.x_min);
  const double sy = (height - top - bottom) / (plot.y_max - plot.y_min);
  auto to_pixel = [&] (double x, double y) {
    return cv::Point (static_cast<int> (std::lround (left + (x - plot.x_min) * sx)),
                      static_cast<int> (std::lround (height - bottom - (y - plot.y_min) * sy)));
  };
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  auto label = [&] (double v) {
    char text[32];
    std::snprintf (text, sizeof text, "%g", std::abs (v) < 1e-12 ? 0.0 : v);
    return std::string (text);
  };
  for (double x = plot.x_min; x <= plot.x_max + 1e-9; x += plot.x_tick)
  {
    cv::line (image, to_pixel (x, plot.y_min), to_pixel (x, plot.y_max), cv::Scalar (225, 225, 225), 1);
    cv::putText (image, label (x), to_pixel (x, plot.y_min) + cv::Point (-8, 20), font, 0.45, cv::Scalar (0, 0, 0), 1,
                 cv::LINE_AA);
  }
  for (double y = plot.y_min; y <= plot.y_max + 1e-9; y += plot.y_tick)
  {
    cv::line (image, to_pixel (plot.x_min, y), to_pixel (plot.x_max, y), cv::Scalar (225, 225, 225), 1);
    cv::putText (image, label (y), to_pixel (plot.x_min, y) + cv::Point (-45, 5), font, 0.45, cv::Scalar (0, 0, 0), 1,
                 cv::LINE_AA);
  }
  cv::rectangle (image, to_pixel (plot.x_min, plot.y_max), to_pixel (plot.x_max, plot.y_min), cv::Scalar (0, 0, 0), 1);
  cv::putText (image, plot.title, cv::Point (left, 25), font, 0.6, cv::Scalar (0, 0, 0), 1, cv::LINE_AA);
  cv::putText (image, plot.x_label, cv::Point (width / 2 - 40, height - 15), font, 0.5, cv::Scalar (0, 0, 0), 1,
               cv::LINE_AA);
  cv::putText (image, plot.y_label, cv::Point (5, top - 8), font, 0.5, cv::Scalar (0, 0, 0), 1, cv::LINE_AA);
  // The legend moves left as far as its longest name needs.
  int legend_width = 170;
  for (const auto &s : plot.series)
  {
    int baseline = 0;
    legend_width = std::max (legend_width, 42 + cv::getTextSize (s.name, font, 0.5, 1, &baseline).width);
  }
  for (std::size_t i = 0; i < plot.series.size (); ++i)
  {
    const auto &s = plot.series[i];
    for (std::size_t j = 1; j < s.points.size (); ++j)
      if (std::isfinite (s.points[j - 1].y) && std::isfinite (s.points[j].y))
        cv::line (image, to_pixel (s.points[j - 1].x, s.points[j - 1].y), to_pixel (s.points[j].x, s.points[j].y),
                  s.colour, 2, cv::LINE_AA);
    const cv::Point legend (width - right - legend_width, height - bottom - 20 - 22 * static_cast<int> (plot.series.size () - 1 - i));
    cv::line (image, legend, legend + cv::Point (25, 0), s.colour, 3, cv::LINE_AA);
    cv::putText (image, s.name, legend + cv::Point (32, 5), font, 0.5, cv::Scalar (0, 0, 0), 1, cv::LINE_AA);
  }
  return image;
}
nlohmann::json
personsJson (const std::vector<PersonInfo> &persons)
{
  nlohmann::json doc = nlohmann::json::array ();
  for (std::size_t k = 0; k < persons.size (); ++k)
  {
    const PersonInfo &p = persons[k];
    doc.push_back ({{"id", k},
                    {"pixels", p.points},
                    {"distance", p.distance},
                    {"height", p.top},
                    {"on_floor", p.on_floor},
                    {"too_far", p.too_far},
                    {"hidden", p.hidden}});
  }
  return doc;
}
}  // namespace apps
}  // namespace agex

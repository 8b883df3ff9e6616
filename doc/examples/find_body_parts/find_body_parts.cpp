// The program of doc/tutorial.md: heads, hands and feet in one depth frame, built from
// agex stages the way a PCL user composes PCL stages, then with agex::BodyPartDetector, the
// whole detector in one class. It is built against an installed agex by the test suite
// (test/consumer), which also checks that its detections are agex_detect's, so the
// tutorial's code cannot rot.
//
//   find_body_parts FRAME AGEX_MODEL DETECTOR_MODEL [PICTURES_DIR]
//
// FRAME is a depth frame (.png, .u16 or organized .pcd), AGEX_MODEL an AGEX-point model such
// as <prefix>/share/agex/models/agex_bonn_agex.yml (steps 5-6 use its classifier by hand),
// DETECTOR_MODEL the detector of step 7 (<prefix>/share/agex/models/agex_bonn.yml, the fused
// detector with its forest and sliding-window model beside it). With PICTURES_DIR, one PNG per step is written there.

#include <agex/classification/patch_classifier.h>
#include <agex/detection/body_part_detector.h>
#include <agex/io/dataset.h>
#include <agex/io/frame_io.h>
#include <agex/features/depth_patch_estimation.h>
#include <agex/filters/depth_median_filter.h>
#include <agex/filters/floor_removal.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/spur_filter.h>
#include <agex/filters/surface_segmentation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/common/io.h>
#include <pcl/filters/crop_box.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <limits>
#include <string>
#include <vector>

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace
{
// Pictures for the tutorial: depth as grey (near = bright), meshes coloured, points drawn.
cv::Mat
depthPicture (const Cloud &cloud)
{
  cv::Mat image (static_cast<int> (cloud.height), static_cast<int> (cloud.width), CV_8UC3, cv::Scalar (40, 0, 0));
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u)
    {
      const float z = cloud (u, v).z;
      if (std::isfinite (z))
      {
        const int grey = std::clamp (static_cast<int> (255.f - (z - 1.0f) * 120.f), 30, 255);
        image.at<cv::Vec3b> (v, u) = cv::Vec3b (grey, grey, grey);
      }
    }
  return image;
}

cv::Vec3b
meshColour (std::size_t mesh)
{
  static const cv::Vec3b colours[] = {{80, 200, 255}, {255, 160, 60}, {120, 255, 120}, {200, 120, 255}, {60, 60, 230}};
  return colours[mesh % (sizeof (colours) / sizeof (colours[0]))];
}

void
save (const std::string &dir, const std::string &name, const cv::Mat &image, double scale = 1.0)
{
  if (dir.empty ())
    return;
  cv::Mat scaled;
  cv::resize (image, scaled, cv::Size (), scale, scale, cv::INTER_NEAREST);
  if (!cv::imwrite (dir + "/" + name, scaled))
    throw std::runtime_error (dir + "/" + name + ": cannot write the picture");
}
}  // namespace

int
main (int argc, char **argv)
{
  if (argc < 4)
  {
    std::fprintf (stderr, "usage: %s FRAME AGEX_MODEL DETECTOR_MODEL [PICTURES_DIR]\n", argv[0]);
    return 2;
  }
  const std::string pictures = argc > 4 ? argv[4] : "";
  try
  {
    // Step 1: the frame. An 8-bit Bonn PNG holds depth in units of 16 mm; loadFrame
    // back-projects it (Kinect intrinsics by default) into an organized cloud, NaN = invalid.
    agex::Frame frame = agex::loadFrame (argv[1]);
    Cloud::Ptr cloud = frame.cloud;
    std::printf ("frame: %u x %u points\n", cloud->width, cloud->height);
    save (pictures, "step1_frame.png", depthPicture (*cloud));

    // Step 2: keep the person's box, drop mixed pixels, smooth. The first two are
    // pcl::FilterIndices: with setKeepOrganized the removed points become NaN and the
    // cloud stays organized, which every later agex stage needs.
    Cloud::Ptr boxed (new Cloud);
    pcl::CropBox<pcl::PointXYZ> crop;
    crop.setInputCloud (cloud);
    crop.setMin (Eigen::Vector4f (-0.75f, -1.5f, 1.3f, 1.f));
    crop.setMax (Eigen::Vector4f (0.75f, 1.5f, 2.6f, 1.f));
    crop.setKeepOrganized (true);
    crop.filter (*boxed);

    Cloud::Ptr unmixed (new Cloud);
    agex::MixedPixelFilter<pcl::PointXYZ> mixed;
    mixed.setInputCloud (boxed);
    mixed.setWindowRadius (2);
    mixed.setMinJump (0.05f);     // metres
    mixed.setMaxVeilAngle (15.f);  // degrees
    mixed.setKeepOrganized (true);
    mixed.filter (*unmixed);

    Cloud::Ptr smoothed (new Cloud);
    agex::DepthMedianFilter<pcl::PointXYZ> median;  // pcl::MedianFilter's depths, faster
    median.setInputCloud (unmixed);
    median.setWindowSize (3);
    median.setMaxAllowedMovement (0.05f);
    median.filter (*smoothed);
    save (pictures, "step2_filtered.png", depthPicture (*smoothed));

    // Step 3: take the floor away (the lowest plane roughly perpendicular to the camera's up
    // axis, found by RANSAC, and everything below it), erode thin spurs at the edges, then
    // split what is left into connected surface meshes.
    Cloud::Ptr standing (new Cloud);
    agex::FloorRemoval<pcl::PointXYZ> floor;
    floor.setInputCloud (smoothed);
    floor.setUpAxis (Eigen::Vector3f (0.f, -1.f, 0.f));  // camera y points down
    floor.setMaxTilt (45.f);                            // degrees
    floor.setDistanceThreshold (0.04f);                 // metres
    floor.setKeepOrganized (true);
    floor.filter (*standing);

    Cloud::Ptr body (new Cloud);
    agex::SpurFilter<pcl::PointXYZ> spurs;
    spurs.setInputCloud (standing);
    // In metres at each point's depth (a pixel spans z / f): 3.5 cm off every edge; strands
    // narrower than 3 cm go, wider parts (a forearm) keep 3 cm of their middle.
    spurs.setFocalLength (static_cast<float> (frame.intrinsics.fx));
    spurs.setErosionDepth (0.035f);
    spurs.setMinWidth (0.03f);
    spurs.setMinConnected (6);
    spurs.setDeltaConnected (0.03f);
    spurs.setKeepOrganized (true);
    spurs.filter (*body);

    std::vector<pcl::PointIndices> meshes;
    agex::SurfaceSegmentation<pcl::PointXYZ> segmentation;
    segmentation.setInputCloud (body);
    segmentation.setDeltaConnected (0.03f);  // neighbours closer than 3 cm are connected
    segmentation.setMinMeshSize (body->size () / 1000);
    segmentation.segment (meshes);
    std::printf ("floor found: %s, meshes: %zu\n", floor.getFloorFound () ? "yes" : "no", meshes.size ());
    cv::Mat mesh_picture = depthPicture (*body);
    for (std::size_t m = 0; m < meshes.size (); ++m)
      for (const auto i : meshes[m].indices)
        mesh_picture.at<cv::Vec3b> (i / body->width, i % body->width) = meshColour (m);
    save (pictures, "step3_meshes.png", mesh_picture);

    // Step 4: AGEX interest points, the accumulative geodesic extrema of each mesh, each
    // with an orientation along its limb.
    pcl::PointCloud<agex::InterestPoint> points;
    agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint> agex;
    agex.setInputCloud (body);
    agex.setMeshes (meshes);
    agex.setPointsPerMesh (11);  // the centroid and 10 extrema, as the bundled model was trained
    agex.setDeltaConnected (0.03f);
    agex.compute (points);
    std::printf ("AGEX points: %zu\n", points.size ());
    cv::Mat agex_picture = mesh_picture.clone ();
    for (const auto &p : points)
    {
      const cv::Point pixel (p.u, p.v);
      cv::circle (agex_picture, pixel, 3, cv::Scalar (0, 0, 255), cv::FILLED);
      cv::line (agex_picture, pixel,
                pixel - cv::Point (static_cast<int> (12 * p.orientation[0]), static_cast<int> (12 * p.orientation[1])),
                cv::Scalar (0, 0, 255), 1);
    }
    save (pictures, "step4_agex.png", agex_picture);

    // Step 5: an oriented depth patch around each point, of the size and extent the
    // model was trained with.
    const agex::PatchClassifier classifier = agex::PatchClassifier::load (argv[2]);
    const agex::PatchGeometry geometry = classifier.patchGeometry ();
    pcl::PointCloud<agex::DepthPatch> patches;
    agex::DepthPatchEstimation<pcl::PointXYZ, agex::DepthPatch> estimation;
    estimation.setInputCloud (body);
    estimation.setInterestPoints (pcl::make_shared<pcl::PointCloud<agex::InterestPoint>> (points));
    estimation.setPatchSize (geometry.size);
    estimation.setPatchExtent (geometry.extent);
    estimation.setClampDepth (geometry.clamp);
    estimation.compute (patches);
    if (!pictures.empty () && !patches.empty ())
    {
      cv::Mat strip (geometry.size, geometry.size * static_cast<int> (patches.size ()), CV_8UC1);
      for (std::size_t i = 0; i < patches.size (); ++i)
        for (int r = 0; r < geometry.size; ++r)
          for (int c = 0; c < geometry.size; ++c)
          {
            const float cell = patches[i].at (r, c);  // -clamp (near) .. +clamp (far)
            strip.at<std::uint8_t> (r, static_cast<int> (i) * geometry.size + c) =
                static_cast<std::uint8_t> (std::clamp (127.5f - 127.5f * cell / geometry.clamp, 0.f, 255.f));
          }
      save (pictures, "step5_patches.png", strip, 3.0);
    }

    // Step 6: classify each patch: one confidence per body part; the best one names it.
    std::vector<float> confidences (classifier.classes ());
    cv::Mat parts_picture = depthPicture (*body);
    for (std::size_t i = 0; i < patches.size (); ++i)
    {
      classifier.classify (patches[i], nullptr, confidences.data ());
      const auto best = std::max_element (confidences.begin (), confidences.end ()) - confidences.begin ();
      const char *name = agex::bodyPartName (static_cast<agex::BodyPart> (best));
      std::printf ("point %zu at pixel (%d, %d): %s %.2f\n", i, points[i].u, points[i].v, name, confidences[best]);
      if (confidences[best] >= 0.5f)
        cv::putText (parts_picture, name, cv::Point (points[i].u + 4, points[i].v), cv::FONT_HERSHEY_PLAIN, 0.8,
                     cv::Scalar (0, 0, 255));
    }
    save (pictures, "step6_parts.png", parts_picture);

    // Step 7: all of the above in one class, with the settings stored in the model (the
    // spur depth scaled to the frame's resolution, the desk-top check of the floor, ...) and
    // several detections of one part within the suppression radius reduced to the best.
    auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (argv[3]);
    detector->setInputCloud (cloud);
    std::vector<agex::BodyPartDetection> detections;
    detector->compute (detections);
    for (const auto &d : detections)
      std::printf ("detection: %s at pixel (%d, %d) confidence %.6f\n", agex::bodyPartName (d.part), d.u, d.v,
                   d.confidence);
    return detections.empty () ? 1 : 0;
  }
  catch (const std::exception &e)
  {
    std::fprintf (stderr, "find_body_parts: %s\n", e.what ());
    return 1;
  }
}

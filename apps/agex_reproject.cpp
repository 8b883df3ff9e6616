// agex_reproject: a dataset's real frames and labels re-projected to other distances,
// positions, tilts and sensors (agex::FrameReprojection), written as a new agex dataset
// (doc/apps/agex_reproject.md). The same seed gives the same bytes.

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/reproject_flags.h>
#include <agex/filters/person_segmentation.h>
#include <agex/io/atomic_file.h>
#include <agex/simulation/dataset_reprojection.h>

#include <algorithm>
#include <iostream>
#include <stdexcept>
#include <vector>

namespace
{
/** The floor agex::PersonSegmentation finds in a frame (its defaults: up is -y, within 25
  * degrees; spread over an area). */
bool
findFloor (const pcl::PointCloud<pcl::PointXYZ> &cloud, Eigen::Vector4f &plane)
{
  agex::PersonSegmentation<pcl::PointXYZ> segmentation;
  segmentation.setInputCloud (pcl::PointCloud<pcl::PointXYZ>::ConstPtr (new pcl::PointCloud<pcl::PointXYZ> (cloud)));
  std::vector<pcl::PointIndices> persons;
  segmentation.segment (persons);
  plane = segmentation.getFloorPlane ();
  return segmentation.getFloorFound ();
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::apps::ReprojectFlags flags;
  try
  {
    if (!agex::apps::parseReprojectFlags (argc, argv, flags))
      return 0;
    const agex::apps::DatasetSelection selection = agex::apps::selectDataset (flags.dataset_spec, flags.keyframes_only);
    if (selection.frame_ids.empty ())
      throw std::runtime_error (flags.dataset_spec + ": no frames selected" +
                                (flags.keyframes_only ? " (no keyframes among them)" : ""));
    agex::InputFiles read (agex::apps::datasetFiles (selection.dataset));
    read.addTree (selection.dataset.directory ());
    agex::apps::checkOutputPath (flags.output, agex::apps::OutputKind::Dataset, read, flags.force);

    agex::DatasetReprojectionOptions options = flags.options;
    if (flags.source_depth_step_auto)
      options.mesh.depth_quantum = agex::depthQuantumOf (selection.dataset.info ());
    if (flags.floor == "auto")
      options.find_floor = findFloor;
    agex::apps::Progress progress ("re-projected", selection.frame_ids.size ());
    const agex::DatasetReprojectionStats stats =
        agex::writeReprojectedDataset (selection.dataset, selection.frame_ids, options, flags.output, flags.force,
                                       [&] (std::size_t done, std::size_t) { progress.step (done); });

    const double copies = static_cast<double> (std::max<std::size_t> (1, stats.frames_out));
    std::cout << flags.output << ": " << stats.frames_out << " " << flags.sensor << " frames ("
              << options.sensor.width << "x" << options.sensor.height << ") from " << stats.frames_in << " frames";
    if (stats.skipped > 0)
      std::cout << " (" << stats.skipped << " left out: no person depth to move to --distance)";
    std::cout << ", " << stats.visible_labels << " of " << stats.labels << " labels visible";
    if (stats.dropped_labels > 0)
      std::cout << ", " << stats.dropped_labels << " left out (no 3D tip, or behind the camera)";
    if (options.find_floor)
      std::cout << "; floor found and rendered in " << stats.with_floor << " of " << stats.frames_in << " frames";
    std::cout << "\n  source depth step max(" << options.mesh.depth_quantum << ", " << options.mesh.depth_step_growth
              << " z^2) m; mesh " << stats.mesh_ms / copies << " ms, render " << stats.render_ms / copies
              << " ms, write " << stats.write_ms / copies << " ms per frame on one thread\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_reproject: error: " << e.what () << "\n";
    return 1;
  }
}

#pragma once
// The flags that choose a detector (--model, --forest, --detector-mode, --forest-stride),
// shared by agex_detect, agex_eval and agex_bench, and the detector they load.

#include <agex/detection/body_part_detector.h>
#include <agex/io/frame_io.h>

#include <boost/program_options/options_description.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** What the flags asked for. */
struct DetectorChoice
{
  std::string model;   ///< model file (default: the bundled model)
  std::string forest;  ///< forest: our model file, a PCL tree file or a directory of them
  std::string mode;  ///< agex, fused or forest; empty: the model's own kind
  int forest_stride = 1;
  float cascade_min_confidence = BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence;
  float cascade_miss_rate = BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMissRate;
  TipRefinementParams tip_refinement;
  std::string window_model;  ///< fused models: a sliding-window model whose scores blend in (empty: the model's own)
  float window_weight = -1.f;  ///< < 0: the fused model's own weight, else BodyPartDetector::kDefaultWindowWeight
  std::string forest_input = "automatic";  ///< forest mode: automatic, persons or meshes (agex::ForestInput)
  std::string forest_parts = "blobs";    ///< forest mode: blobs or modes (agex::PartProposals)
};

/** --model, --forest, --detector-mode, --forest-stride, --forest-input, --forest-parts; model_default is --model's default. */
boost::program_options::options_description detectorOptionsDescription (DetectorChoice &choice,
                                                                        const std::string &model_default);

/** A loaded detector's parts, shared by every thread's BodyPartDetector. */
struct LoadedDetector
{
  DetectorModel::ConstPtr model;
  BodyPartForest::ConstPtr forest;
  DetectorMode mode = DetectorMode::Model;
  int forest_stride = 1;
  float cascade_min_confidence = BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence;
  float cascade_miss_rate = BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMissRate;
  TipRefinementParams tip_refinement;
  DetectorModel::ConstPtr window_model;
  float window_weight = 0.f;
  ForestPartSettings forest_parts;
  /** What names the parts: "agex", "fused", "sliding_window" (the model's kind) or "forest". */
  std::string mode_name;

  /** Gives detector the model, forest, mode, stride and forest-mode settings. */
  void configure (BodyPartDetector<pcl::PointXYZ> &detector) const;
  /** The files it was loaded from (what no output may overwrite): the model first. */
  std::vector<std::string> files;
  std::string forest_file;  ///< the forest's file or directory (empty: none)
  std::string window_file;  ///< the window model's file (empty: none)
};

/** \brief Loads what choice names, checking the combination: an AGEX model for the agex
  * mode (kind the kind asked for), a forest for the forest mode.
  * \throws std::runtime_error or agex::ModelError naming the flag or the file */
LoadedDetector loadDetector (const DetectorChoice &choice, DetectorKind kind = DetectorKind::Agex);
}  // namespace apps
}  // namespace agex

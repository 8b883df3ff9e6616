#pragma once
// agex_eval's flags: the mode, the dataset, the reports and plots, each mode's settings, the
// detector, the weak part labels and the depth pipeline (without its --k), checked before
// anything is read.

#include <agex/apps/output_guard.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/detector_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/detection/detector_model.h>
#include <agex/detection/part_label_training.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct EvalFlags
{
  EvalFlags ();

  std::string mode;  ///< coverage, detect, compare or parts
  std::string dataset_dir;
  std::string json_path, plot_path, plots_dir, overlay_dir;
  std::string agex_model_path, sw_model_path, fused_model_path;  ///< compare's (default: the bundled ones)
  float min_iou = 0.5f, radius = 0.10f;
  SlidingWindowParams window_override{0, {}};
  int k = 5;
  bool keyframes = false, details = false;
  std::string shard;                     ///< detect: K/N, parsed when the detector runs
  std::vector<std::string> merge_parts;  ///< detect --merge
  DepthPipelineParams params;
  DetectorChoice detector;
  WeakPartLabelParams weak;
};

/** \brief Parses agex_eval's command line into flags and checks them: only detect shares its
  * frames (distributed: run by mpirun, --shard, --merge); --merge needs nothing more; every
  * other run a --dataset, ranges and a known mode.
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error, std::invalid_argument or boost::program_options::error naming
  *         the flag */
bool parseEvalFlags (int argc, char **argv, bool distributed, EvalFlags &flags);

/** \brief Refuses outputs that would overwrite what is read (the dataset, the models and the
  * forest) or a file of another kind: --json a JSON report, --plot a PNG, --plots and
  * --overlay-dir directories. \throws std::runtime_error naming the path */
void checkEvalOutputs (const EvalFlags &flags, const DatasetSelection &selection);

/** How agex_eval tells its own earlier report (of any mode) by its keys. */
OutputRecogniser evalReportRecogniser ();

/** The PNGs agex_eval MODE writes into --plots DIR (checked before any is written). */
std::vector<std::string> evalPlotFiles (const std::string &mode, const std::string &plots_dir);
}  // namespace apps
}  // namespace agex

#pragma once
// agex_eval's modes: each runs one evaluation of the library (agex::CoverageEvaluation,
// agex::DetectionEvaluation, agex::PartLabelEvaluation) over a dataset's frames, prints the
// figures and writes the JSON report and plots.

#include <agex/apps/batch_runs.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/detector_flags.h>
#include <agex/detection/detector_model.h>
#include <agex/detection/part_label_training.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** agex_eval coverage: labelled tips among the first k AGEX extrema (and the curve to 20). */
int evaluateCoverage (const DatasetSelection &selection, DepthPipelineParams params, int k, float radius,
                      bool keyframes_only, bool details, const std::string &json_path, const std::string &plot_path);

/** agex_eval detect: AP, precision-recall, confusion and orientation error of a detector.
  * Under mpirun each rank evaluates its share of the frames (shardRange) and rank 0 merges
  * the evaluations' states in rank order and reports; with --shard (shard.given) only that
  * part is evaluated, and the report (json_path, required) also holds "shard" and "state",
  * for mergeDetectionEvaluations. */
int evaluateDetection (const DatasetSelection &selection, const LoadedDetector &loaded, float radius,
                       const std::string &json_path, const std::string &plots_dir, ProcessGroup &group,
                       const Shard &shard);

/** agex_eval detect --merge: the reports of every shard of one --shard run (each once, any
  * order) reduced to the report of the whole run (frames in dataset order).
  * \throws std::runtime_error naming the report: not a shard's, of another run, a shard twice
  *         or missing */
int mergeDetectionEvaluations (const std::vector<std::string> &parts, const std::string &json_path,
                               const std::string &plots_dir);

/** agex_eval compare: the AGEX detector against the sliding-window baseline (the paper's Fig. 7),
  * and the fused detector beside them when fused_model_path is not empty. */
int compareDetectors (const DatasetSelection &selection, const std::string &agex_model_path,
                      const std::string &sw_model_path, const std::string &fused_model_path,
                      const SlidingWindowParams &window_override, float radius, float min_iou,
                      const std::string &json_path, const std::string &plots_dir);

/** agex_eval parts: the forest's per-pixel labels against exact (part-label images) or weak
  * classes, on the pixels the model's pipeline keeps; part maps into overlay_dir. */
int evaluatePartLabels (const DatasetSelection &selection, const LoadedDetector &loaded, const WeakPartLabelParams &weak,
                        const std::string &json_path, const std::string &overlay_dir);
}  // namespace apps
}  // namespace agex

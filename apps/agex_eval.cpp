// agex_eval: evaluations on labelled agex datasets.
//   agex_eval coverage --dataset DIR[@SEQ,...] [--k K] [--radius R] [--keyframes] [--json FILE] [--plot FILE.png]
//   agex_eval detect --dataset DIR[@SEQ,...] [--model M] [--detector-mode agex|forest --forest F] [--json FILE]
//                    [--shard K/N]    (or under mpirun -n N: the ranks share the frames)
//   agex_eval detect --merge PART.json... --json FILE
//   agex_eval compare --dataset DIR[@SEQ,...] [--model-agex M] [--model-sw M] [--json FILE] [--plots DIR]
//   agex_eval parts --dataset DIR[@SEQ,...] --forest F [--json FILE] [--overlay-dir DIR]
// coverage: how often each labelled body part is among the first k AGEX points.
// detect: precision and recall of the body-part detector.
// compare: the AGEX detector against the sliding-window baseline (the paper's Fig. 7).
// parts: per-pixel accuracy of a body-part forest.

#include <agex/apps/batch_runs.h>
#include <agex/apps/eval_flags.h>
#include <agex/apps/evaluation_runs.h>

#include <iostream>
#include <memory>

int
main (int argc, char **argv)
{
  agex::apps::EvalFlags flags;
  std::unique_ptr<agex::apps::ProcessGroup> group;  // MPI, when run by mpirun: to the end of main
  try
  {
    group = agex::apps::joinProcessGroup (argc, argv);
    if (!agex::apps::parseEvalFlags (argc, argv, group->distributed (), flags))
      return 0;
    if (!flags.merge_parts.empty ())
      return agex::apps::mergeDetectionEvaluations (flags.merge_parts, flags.json_path, flags.plots_dir);
    const auto selection = agex::apps::selectDataset (flags.dataset_dir, flags.keyframes);
    agex::apps::checkEvalOutputs (flags, selection);
    if (flags.mode == "coverage")
      return agex::apps::evaluateCoverage (selection, flags.params, flags.k, flags.radius, flags.keyframes,
                                           flags.details, flags.json_path, flags.plot_path);
    if (flags.mode == "compare")
      return agex::apps::compareDetectors (selection, flags.agex_model_path, flags.sw_model_path,
                                           flags.fused_model_path, flags.window_override, flags.radius, flags.min_iou,
                                           flags.json_path, flags.plots_dir);
    if (flags.mode == "parts" && flags.detector.forest.empty ())
      throw std::runtime_error ("agex_eval parts needs --forest");
    const agex::apps::LoadedDetector loaded = agex::apps::loadDetector (flags.detector);
    if (flags.mode == "parts")
      return agex::apps::evaluatePartLabels (selection, loaded, flags.weak, flags.json_path, flags.overlay_dir);
    const agex::apps::Shard shard = flags.shard.empty () ? agex::apps::Shard () : agex::apps::parseShard (flags.shard);
    return agex::apps::evaluateDetection (selection, loaded, flags.radius, flags.json_path, flags.plots_dir, *group,
                                          shard);
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_eval: error: " << e.what () << "\n";
    return 1;
  }
}

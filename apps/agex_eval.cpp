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
#include <agex/apps/command_line.h>
#include <agex/apps/evaluation_runs.h>
#include <agex/apps/forest_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <filesystem>
#include <iostream>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  agex::DepthPipelineParams params;
  agex::apps::DetectorChoice choice;
  agex::WeakPartLabelParams weak;
  std::vector<std::string> vector_flags;
  std::string mode, dataset_dir, json_path, plot_path, plots_dir, overlay_dir,
      agex_model_path = AGEX_BUNDLED_AGEX_MODEL, sw_model_path = AGEX_BUNDLED_SW_MODEL,
      fused_model_path = AGEX_BUNDLED_MODEL;
  float min_iou = 0.5f, radius = 0.10f;
  agex::SlidingWindowParams window_override{0, {}};
  int k = 5;
  bool keyframes = false, details = false;
  std::string shard;
  std::vector<std::string> merge_parts;

  po::options_description general ("agex_eval coverage|detect|compare|parts --dataset DIR[@SEQ,...] [options]\n"
                                    "Evaluates AGEX coverage, body-part detection or a forest's part labels on a\n"
                                    "labelled agex dataset, or compares the AGEX detector with the sliding-window baseline");
  general.add_options () ("help,h", "show this help") ("mode", po::value (&mode), "coverage, detect, compare or parts")
    ("dataset", po::value (&dataset_dir), "dataset directory")
    ("k", po::value (&k)->default_value (k), "number of extrema per mesh scored")
    ("radius", po::value (&radius)->default_value (radius, "0.1"), "metres between a tip and a point that covers it")
    ("keyframes", po::bool_switch (&keyframes), "score keyframes only")
    ("details", po::bool_switch (&details), "list every scored label in the JSON (first rank, nearest point)")
    ("json", po::value (&json_path), "write the report as JSON here")
    ("plot", po::value (&plot_path), "coverage: write the coverage-vs-k curve (k up to 20) as PNG here")
    ("plots", po::value (&plots_dir),
     "detect: write precision_recall.png into this directory; compare: compare_{head,hand,foot}.png")
    ("overlay-dir", po::value (&overlay_dir), "parts: write each frame's part map into this directory")
    ("model-agex", po::value (&agex_model_path)->default_value (agex_model_path), "compare: the AGEX model (default: the bundled model)")
    ("model-sw", po::value (&sw_model_path)->default_value (sw_model_path),
     "compare: the sliding-window model (default: the bundled one)")
    ("model-fused", po::value (&fused_model_path)->default_value (fused_model_path),
     "compare: the fused model beside them (default: the bundled detector; empty: none)")
    ("min-iou", po::value (&min_iou)->default_value (min_iou, "0.5"),
     "compare: box overlap (intersection over union) above which a detection matches a part")
    ("window-stride", po::value (&window_override.stride),
     "compare: pixels between window centres (default: the sliding-window model's)")
    ("window-scales", po::value (&window_override.scales)->multitoken (),
     "compare: window extents over the trained extent (default: the sliding-window model's)")
    ("shard", po::value (&shard), "detect: only the K-th (0-based) of N equal parts of the frames (K/N), for job arrays")
    ("merge", po::value (&merge_parts)->multitoken (), "detect: reduce the --json reports of every --shard run into --json");
  // The pipeline's own --k (points per mesh) would make --k ambiguous: coverage sets it.
  po::options_description pipeline ("Pipeline (coverage)");
  const po::options_description pipeline_all = agex::apps::pipelineOptionsDescription (params, vector_flags);
  for (const auto &option : pipeline_all.options ())
    if (option->long_name () != "k")
      pipeline.add (option);
  po::options_description all;
  all.add (general).add (agex::apps::detectorOptionsDescription (choice, AGEX_BUNDLED_MODEL))
     .add (agex::apps::weakLabelOptions (weak)).add (pipeline);
  po::positional_options_description positional;
  positional.add ("mode", 1);

  std::unique_ptr<agex::apps::ProcessGroup> group;  // MPI, when run by mpirun: to the end of main
  try
  {
    group = agex::apps::joinProcessGroup (argc, argv);
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if ((group->distributed () || !shard.empty () || !merge_parts.empty ()) && mode != "detect")
      throw std::runtime_error ("only agex_eval detect shares its frames (mpirun, --shard, --merge)");
    if (!merge_parts.empty ())
      return agex::apps::mergeDetectionEvaluations (merge_parts, json_path, plots_dir);
    agex::apps::finishPipelineOptions (vector_flags, params);
    weak.validate ();
    if (dataset_dir.empty ())
      throw std::runtime_error ("--dataset is required (see --help)");
    if (k < 1 || k > 200 || !(radius > 0.f && radius <= 1.f) || !(min_iou > 0.f && min_iou < 1.f))
      throw std::runtime_error ("--k must lie in [1, 200], --radius in (0, 1] m and --min-iou in (0, 1)");
    if (mode != "coverage" && mode != "detect" && mode != "compare" && mode != "parts")
      throw std::runtime_error ("unknown mode '" + mode + "' (expected coverage, detect, compare or parts)");
    const auto selection = agex::apps::selectDataset (dataset_dir, keyframes);
    agex::InputFiles read;
    read.addTree (selection.dataset.directory ());
    for (const auto &model : {choice.model, agex_model_path, sw_model_path, fused_model_path, choice.forest})
      if (!model.empty ())
        std::filesystem::is_directory (model) ? read.addTree (model) : read.add (model);
    if (!json_path.empty ())
      agex::apps::checkOutputPath (json_path, agex::apps::OutputKind::Json, read);
    if (!plot_path.empty ())
      agex::apps::checkOutputPath (plot_path, agex::apps::OutputKind::Png, read);
    for (const auto &dir : {plots_dir, overlay_dir})
      if (!dir.empty () && std::filesystem::exists (dir) && !std::filesystem::is_directory (dir))
        throw std::runtime_error (dir + ": a file, not a directory");
      else if (!dir.empty ())
        read.checkOutput (dir);
    if (mode == "coverage")
      return agex::apps::evaluateCoverage (selection, params, k, radius, keyframes, details, json_path, plot_path);
    if (mode == "compare")
      return agex::apps::compareDetectors (selection, agex_model_path, sw_model_path, fused_model_path, window_override, radius, min_iou,
                                           json_path, plots_dir);
    if (mode == "parts" && choice.forest.empty ())
      throw std::runtime_error ("agex_eval parts needs --forest");
    const agex::apps::LoadedDetector loaded = agex::apps::loadDetector (choice);
    if (mode == "parts")
      return agex::apps::evaluatePartLabels (selection, loaded, weak, json_path, overlay_dir);
    return agex::apps::evaluateDetection (selection, loaded, radius, json_path, plots_dir, *group,
                                          shard.empty () ? agex::apps::Shard () : agex::apps::parseShard (shard));
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_eval: error: " << e.what () << "\n";
    return 1;
  }
}

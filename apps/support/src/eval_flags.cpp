#include <agex/apps/eval_flags.h>

#include <agex/apps/command_line.h>
#include <agex/apps/forest_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/common/body_part.h>

#include <boost/program_options.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
EvalFlags::EvalFlags ()
  : agex_model_path (kBundledAgexModelFile), sw_model_path (kBundledSlidingWindowModelFile),
    fused_model_path (kBundledModelFile)
{
}

bool
parseEvalFlags (int argc, char **argv, bool distributed, EvalFlags &flags)
{
  std::vector<std::string> vector_flags;
  po::options_description general ("agex_eval coverage|detect|compare|parts --dataset DIR[@SEQ,...] [options]\n"
                                    "Evaluates AGEX coverage, body-part detection or a forest's part labels on a\n"
                                    "labelled agex dataset, or compares the AGEX detector with the sliding-window baseline");
  general.add_options () ("help,h", "show this help") ("mode", po::value (&flags.mode), "coverage, detect, compare or parts")
    ("dataset", po::value (&flags.dataset_dir), "dataset directory")
    ("k", po::value (&flags.k)->default_value (flags.k), "number of extrema per mesh scored")
    ("radius", po::value (&flags.radius)->default_value (flags.radius, "0.1"), "metres between a tip and a point that covers it")
    ("keyframes", po::bool_switch (&flags.keyframes), "score keyframes only")
    ("details", po::bool_switch (&flags.details), "list every scored label in the JSON (first rank, nearest point)")
    ("json", po::value (&flags.json_path), "write the report as JSON here")
    ("plot", po::value (&flags.plot_path), "coverage: write the coverage-vs-k curve (k up to 20) as PNG here")
    ("plots", po::value (&flags.plots_dir),
     "detect: write precision_recall.png into this directory; compare: compare_{head,hand,foot}.png")
    ("overlay-dir", po::value (&flags.overlay_dir), "parts: write each frame's part map into this directory")
    ("model-agex", po::value (&flags.agex_model_path)->default_value (flags.agex_model_path), "compare: the AGEX model (default: the bundled model)")
    ("model-sw", po::value (&flags.sw_model_path)->default_value (flags.sw_model_path),
     "compare: the sliding-window model (default: the bundled one)")
    ("model-fused", po::value (&flags.fused_model_path)->default_value (flags.fused_model_path),
     "compare: the fused model beside them (default: the bundled detector; empty: none)")
    ("min-iou", po::value (&flags.min_iou)->default_value (flags.min_iou, "0.5"),
     "compare: box overlap (intersection over union) above which a detection matches a part")
    ("window-stride", po::value (&flags.window_override.stride),
     "compare: pixels between window centres (default: the sliding-window model's)")
    ("window-scales", po::value (&flags.window_override.scales)->multitoken (),
     "compare: window extents over the trained extent (default: the sliding-window model's)")
    ("shard", po::value (&flags.shard), "detect: only the K-th (0-based) of N equal parts of the frames (K/N), for job arrays")
    ("merge", po::value (&flags.merge_parts)->multitoken (), "detect: reduce the --json reports of every --shard run into --json");
  // The pipeline's own --k (points per mesh) would make --k ambiguous: coverage sets it.
  po::options_description pipeline ("Pipeline (coverage)");
  const po::options_description pipeline_all = pipelineOptionsDescription (flags.params, vector_flags);
  for (const auto &option : pipeline_all.options ())
    if (option->long_name () != "k")
      pipeline.add (option);
  po::options_description all;
  all.add (general).add (detectorOptionsDescription (flags.detector, kBundledModelFile))
     .add (weakLabelOptions (flags.weak)).add (pipeline);
  po::positional_options_description positional;
  positional.add ("mode", 1);

  std::vector<std::string> given;
  if (!parseCommandLine (argc, argv, all, positional, &given))
    return false;
  if ((distributed || !flags.shard.empty () || !flags.merge_parts.empty ()) && flags.mode != "detect")
    throw std::runtime_error ("only agex_eval detect shares its frames (mpirun, --shard, --merge)");
  if (!flags.merge_parts.empty ())
    return true;
  if (flags.mode != "coverage" && flags.mode != "detect" && flags.mode != "compare" && flags.mode != "parts")
    throw std::runtime_error ("unknown mode '" + flags.mode + "' (expected coverage, detect, compare or parts)");
  // A flag of another mode would be ignored without a word (agex_eval detect takes its
  // pipeline from the model, not from --spur-iterations): refused instead, naming the modes.
  std::map<std::string, std::set<std::string>> modes_of = {
      {"k", {"coverage"}},          {"details", {"coverage"}},      {"plot", {"coverage"}},
      {"plots", {"detect", "compare"}}, {"overlay-dir", {"parts"}}, {"model-agex", {"compare"}},
      {"model-sw", {"compare"}},    {"model-fused", {"compare"}},   {"min-iou", {"compare"}},
      {"window-stride", {"compare"}}, {"window-scales", {"compare"}}};
  for (const auto &option : pipeline.options ())
    modes_of[option->long_name ()] = {"coverage"};
  // Descriptions of scratch settings: describing flags.detector again would reset its --model.
  WeakPartLabelParams scratch_weak;
  DetectorChoice scratch_detector;
  const po::options_description weak = weakLabelOptions (scratch_weak),
                                 detector = detectorOptionsDescription (scratch_detector, kBundledModelFile);
  for (const auto &option : weak.options ())
    modes_of[option->long_name ()] = {"parts"};
  for (const auto &option : detector.options ())
    modes_of[option->long_name ()] = {"detect", "parts"};
  for (const auto &name : given)
  {
    const auto it = modes_of.find (name);
    if (it == modes_of.end () || it->second.count (flags.mode))
      continue;
    std::string modes;
    for (const auto &m : it->second)
      modes += (modes.empty () ? "" : " or ") + m;
    throw std::runtime_error ("--" + name + " applies to agex_eval " + modes + ", not to agex_eval '" + flags.mode +
                              "'" + (flags.mode == "detect" && it->second.count ("coverage")
                                         ? " (detect runs the model's own pipeline: change it in a copy of the "
                                           "model with scripts/set_model_pipeline.py)"
                                         : ""));
  }
  finishPipelineOptions (vector_flags, flags.params);
  flags.weak.validate ();
  if (flags.dataset_dir.empty ())
    throw std::runtime_error ("--dataset is required (see --help)");
  if (flags.k < 1 || flags.k > 200 || !(flags.radius > 0.f && flags.radius <= 1.f) ||
      !(flags.min_iou > 0.f && flags.min_iou < 1.f))
    throw std::runtime_error ("--k must lie in [1, 200], --radius in (0, 1] m and --min-iou in (0, 1)");
  return true;
}

OutputRecogniser
evalReportRecogniser ()
{
  // One key set per mode: coverage, detect, parts, compare.
  std::vector<OutputRecogniser> modes;
  for (const auto &keys : std::vector<std::vector<std::string>>{
           {"dataset", "keyframes_only"}, {"dataset", "detector_mode"}, {"dataset", "forest"}, {"agex", "sliding_window"}})
    modes.push_back (jsonReportWith (keys));
  return [modes] (const std::string &path) {
    std::string why;
    for (const auto &mode : modes)
      if ((why = mode (path)).empty ())
        return why;
    return why.find ("JSON object without") == std::string::npos
               ? why
               : std::string ("exists and is a JSON object with none of the keys of an agex_eval report");
  };
}

std::vector<std::string>
evalPlotFiles (const std::string &mode, const std::string &plots_dir)
{
  if (plots_dir.empty ())
    return {};
  // evaluation_runs.cpp: detect draws one precision-recall plot, compare one per part.
  std::vector<std::string> names{"precision_recall.png"};
  if (mode == "compare")
  {
    names.clear ();
    for (int c = 0; c < kBodyPartCount; ++c)
      names.push_back ("compare_" + std::string (bodyPartName (static_cast<BodyPart> (c))) + ".png");
  }
  std::vector<std::string> files;
  for (const std::string &name : names)
    files.push_back ((std::filesystem::path (plots_dir) / name).string ());
  return files;
}

void
checkEvalOutputs (const EvalFlags &flags, const DatasetSelection &selection)
{
  InputFiles read;
  read.addTree (selection.dataset.directory ());
  for (const auto &model :
       {flags.detector.model, flags.agex_model_path, flags.sw_model_path, flags.fused_model_path, flags.detector.forest,
        flags.detector.window_model})
    if (!model.empty ())
      std::filesystem::is_directory (model) ? read.addTree (model) : read.add (model);
  if (!flags.json_path.empty ())
    checkOutputPath (flags.json_path, "agex_eval report", evalReportRecogniser (), read);
  if (!flags.plot_path.empty ())
    checkOutputPath (flags.plot_path, OutputKind::Png, read);
  for (const auto &dir : {flags.plots_dir, flags.overlay_dir})
    if (!dir.empty () && std::filesystem::exists (dir) && !std::filesystem::is_directory (dir))
      throw std::runtime_error (dir + ": a file, not a directory");
    else if (!dir.empty ())
      read.checkOutput (dir);
  // The PNGs these folders get (evaluation_runs.cpp), checked before any is written.
  std::vector<std::string> pngs = evalPlotFiles (flags.mode, flags.plots_dir);
  if (!flags.overlay_dir.empty ())
    for (const std::string &id : selection.frame_ids)
      pngs.push_back ((std::filesystem::path (flags.overlay_dir) / (id + ".png")).string ());
  checkPngsInFolder (pngs, read);
}
}  // namespace apps
}  // namespace agex

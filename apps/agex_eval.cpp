// agex_eval: evaluations on labelled agex datasets.
//   agex_eval coverage --dataset DIR[@SEQ,...] --k K --radius R [--keyframes] --json FILE [--plot FILE.png]
// coverage: how often each labelled body part is among the first k AGEX points.

#include <agex/apps/body_parts.h>
#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/coverage.h>
#include <agex/apps/depth_pipeline.h>
#include <agex/apps/output.h>
#include <agex/common/atomic_file.h>
#include <agex/classification/patch_classifier.h>
#include <agex/common/dataset.h>

#include <filesystem>

#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <iostream>

namespace po = boost::program_options;

namespace
{
int
evaluateCoverage (const agex::apps::DatasetSelection &selection, agex::apps::PipelineParams params, int k,
                  float radius, bool keyframes_only, bool details, const std::string &json_path,
                  const std::string &plot_path)
{
  constexpr int kCurveMax = 20;
  const int max_k = std::max (k, kCurveMax);
  params.k = max_k + 1;  // the centroid and max_k extrema per mesh
  agex::apps::CoverageEvaluation evaluation (max_k, radius);
  evaluation.setDetailK (k);

  const agex::Dataset &dataset = selection.dataset;
  const std::vector<std::string> &ids = selection.frame_ids;
  agex::apps::Progress progress ("evaluated", ids.size ());
  double total_ms = 0.0;
  std::size_t meshes = 0;
  for (std::size_t i = 0; i < ids.size (); ++i)
  {
    const auto cloud = dataset.loadFrame (ids[i]);
    const agex::apps::PipelineResult result = agex::apps::runDepthPipeline (cloud, params);
    total_ms += result.ms.back ().second;
    meshes += result.meshes.size ();
    evaluation.addFrame (result.interest_points, dataset.labelsOf (ids[i]));
    progress.step (i + 1);
  }

  nlohmann::json doc = evaluation.report (k);
  doc["dataset"] = dataset.directory ();
  doc["keyframes_only"] = keyframes_only;
  doc["pipeline_ms_per_frame"] = ids.empty () ? 0.0 : total_ms / ids.size ();
  doc["meshes_per_frame"] = ids.empty () ? 0.0 : static_cast<double> (meshes) / ids.size ();
  if (details)
    doc["labels_detail"] = evaluation.details ();
  if (!json_path.empty ())
    agex::apps::writeJson (json_path, doc);

  std::cout << dataset.directory () << ": " << ids.size () << " frames, k = " << k << " extrema, R = " << radius
            << " m\n";
  for (int c = 0; c < agex::kBodyPartCount; ++c)
  {
    const auto part = static_cast<agex::BodyPart> (c);
    std::printf ("  %-5s coverage %.3f (centroid counted: %.3f) of %zu labels, orientation median %.1f deg\n",
                 agex::bodyPartName (part), evaluation.coverage (part, k), evaluation.coverageCountingCentroid (part, k),
                 evaluation.labelCount (part), evaluation.orientationMedianDeg (part));
  }

  if (!plot_path.empty ())
  {
    agex::apps::Plot plot;
    plot.title = "AGEX coverage: tips within " + std::to_string (static_cast<int> (radius * 100 + 0.5)) +
                 " cm of the first k extrema (" + std::to_string (ids.size ()) + " frames)";
    plot.x_label = "k (extrema)";
    plot.y_label = "coverage";
    plot.x_min = 0;
    plot.x_max = max_k;
    plot.x_tick = 2;
    for (int c = 0; c < agex::kBodyPartCount; ++c)
    {
      const auto part = static_cast<agex::BodyPart> (c);
      agex::apps::Plot::Series series{agex::bodyPartName (part), agex::apps::bodyPartColour (c), {}};
      series.points.emplace_back (0.0, 0.0);
      for (int kk = 1; kk <= max_k; ++kk)
        series.points.emplace_back (kk, evaluation.coverage (part, kk));
      plot.series.push_back (series);
    }
    agex::apps::writePng (plot_path, agex::apps::renderPlot (plot));
  }
  return 0;
}
int
evaluateDetection (const agex::apps::DatasetSelection &selection, const std::string &model_path, float radius,
                   const std::string &json_path, const std::string &plots_dir)
{
  const agex::PatchClassifier classifier = agex::PatchClassifier::load (model_path);
  const agex::apps::DetectorSettings settings = agex::apps::DetectorSettings::fromJson (classifier.metadata ());
  agex::apps::DetectionEvaluation evaluation (radius);
  agex::apps::Progress progress ("evaluated", selection.frame_ids.size ());
  std::vector<double> frame_ms;
  for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
  {
    const auto &id = selection.frame_ids[i];
    const auto cloud = selection.dataset.loadFrame (id);
    const auto start = std::chrono::steady_clock::now ();
    const auto prepared = agex::apps::runDepthPipeline (cloud, settings.pipeline);
    const auto detections = agex::apps::detectBodyParts (prepared, classifier, settings.patch);
    frame_ms.push_back (std::chrono::duration<double, std::milli> (std::chrono::steady_clock::now () - start).count ());
    evaluation.addFrame (detections, selection.dataset.labelsOf (id));
    progress.step (i + 1);
  }
  constexpr float kConfusionThreshold = 0.75f;
  nlohmann::json doc = evaluation.report (kConfusionThreshold);
  doc["dataset"] = selection.dataset.directory ();
  doc["model"] = model_path;
  std::sort (frame_ms.begin (), frame_ms.end ());
  doc["ms_per_frame_median"] = frame_ms.empty () ? 0.0 : frame_ms[frame_ms.size () / 2];
  if (!json_path.empty ())
    agex::apps::writeJson (json_path, doc);
  std::cout << selection.dataset.directory () << ": " << selection.frame_ids.size () << " frames\n";
  for (int c = 0; c < agex::kBodyPartCount; ++c)
  {
    const auto part = static_cast<agex::BodyPart> (c);
    std::printf ("  %-5s AP %.3f, orientation median %.1f deg\n", agex::bodyPartName (part),
                 evaluation.averagePrecision (part), evaluation.orientationMedianDeg (part));
  }
  if (!plots_dir.empty ())
  {
    std::filesystem::create_directories (plots_dir);
    agex::apps::Plot plot;
    plot.title = "Body-part detection: precision against recall (" + std::to_string (selection.frame_ids.size ()) +
                 " frames)";
    plot.x_label = "recall";
    plot.y_label = "precision";
    for (int c = 0; c < agex::kBodyPartCount; ++c)
    {
      const auto part = static_cast<agex::BodyPart> (c);
      char name[64];
      std::snprintf (name, sizeof name, "%s AP %.2f", agex::bodyPartName (part), evaluation.averagePrecision (part));
      agex::apps::Plot::Series series{name, agex::apps::bodyPartColour (c), {}};
      for (const auto &[recall, precision] : evaluation.precisionRecall (part))
        series.points.emplace_back (recall, precision);
      plot.series.push_back (series);
    }
    agex::apps::writePng ((std::filesystem::path (plots_dir) / "precision_recall.png").string (),
                          agex::apps::renderPlot (plot));
  }
  return 0;
}
}  // namespace

int
main (int argc, char **argv)
{
  agex::apps::PipelineParams params;
  std::vector<std::string> vector_flags;
  std::string mode, dataset_dir, json_path, plot_path, plots_dir, model_path = AGEX_BUNDLED_MODEL;
  int k = 5;
  float radius = 0.10f;
  bool keyframes = false, details = false;

  po::options_description general ("agex_eval coverage|detect --dataset DIR[@SEQ,...] [options]\n"
                                    "Evaluates AGEX coverage or body-part detection on a labelled agex dataset");
  general.add_options () ("help,h", "show this help") ("mode", po::value (&mode), "coverage")
    ("dataset", po::value (&dataset_dir), "dataset directory")
    ("k", po::value (&k)->default_value (k), "number of extrema per mesh scored")
    ("radius", po::value (&radius)->default_value (radius, "0.1"), "metres between a tip and a point that covers it")
    ("keyframes", po::bool_switch (&keyframes), "score keyframes only")
    ("details", po::bool_switch (&details), "list every scored label in the JSON (first rank, nearest point)")
    ("json", po::value (&json_path), "write the report as JSON here")
    ("plot", po::value (&plot_path), "coverage: write the coverage-vs-k curve (k up to 20) as PNG here")
    ("model", po::value (&model_path)->default_value (model_path), "detect: model file (default: the bundled model)")
    ("plots", po::value (&plots_dir), "detect: write precision_recall.png into this directory");
  // The pipeline's own --k (points per mesh, centroid included) would make --k
  // ambiguous; evaluateCoverage sets the pipeline's k from the extrema scored.
  po::options_description pipeline ("Pipeline (defaults isolate a person 1.3-2.6 m in front of the sensor,\n"
                                    "within 0.75 m of its optical axis, as in the Bonn frames)");
  const po::options_description pipeline_all = agex::apps::pipelineOptionsDescription (params, vector_flags);
  for (const auto &option : pipeline_all.options ())
    if (option->long_name () != "k")
      pipeline.add (option);
  po::options_description all;
  all.add (general).add (pipeline);
  po::positional_options_description positional;
  positional.add ("mode", 1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, params);
    if (dataset_dir.empty ())
      throw std::runtime_error ("--dataset is required (see --help)");
    if (k < 1 || !(radius > 0.f))
      throw std::runtime_error ("--k must be at least 1 and --radius positive");
    if (mode == "detect")
      return evaluateDetection (agex::apps::selectDataset (dataset_dir, keyframes), model_path, radius, json_path,
                                plots_dir);
    if (mode == "coverage")
    {
      const agex::apps::DatasetSelection selection = agex::apps::selectDataset (dataset_dir, keyframes);
      const std::string &dir = selection.dataset.directory ();
      for (const auto &out : {json_path, plot_path})
        if (!out.empty ())
          agex::checkOutputIsNotInput (out, {dir + "/dataset.json", dir + "/labels.csv"});
      return evaluateCoverage (selection, params, k, radius, keyframes, details, json_path, plot_path);
    }
    throw std::runtime_error ("unknown mode '" + mode + "' (expected coverage or detect)");
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_eval: error: " << e.what () << "\n";
    return 1;
  }
}

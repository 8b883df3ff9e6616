// agex_train: trains the body-part patch classifier from labelled agex datasets
// and writes one model file holding everything detection needs: for AGEX points (the
// default) or for the sliding-window baseline (--sliding-window).
//   agex_train --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [--sliding-window] [options]

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/classification/patch_classifier.h>
#include <agex/detection/detector_model.h>
#include <agex/detection/training_samples.h>
#include <agex/io/atomic_file.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  agex::DepthPipelineParams params;
  params.k = 11;  // the centroid and 10 extrema per mesh: positives and hard negatives
  agex::PatchGeometry patch;
  patch.size = 41;
  patch.extent = 0.6f;
  patch.clamp = 0.3f;
  agex::PatchClassifierParams classifier_params;
  std::vector<std::string> vector_flags, datasets;
  std::string out;
  int random_negatives = 8;
  float radius = 0.10f;
  bool keyframes = false, sliding_window = false;
  std::uint64_t seed = 1;
  agex::SlidingWindowParams windows;
  int window_negatives = 40, jitter = 3;
  float jitter_radius = 0.04f;

  po::options_description general ("agex_train --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]\n"
                                    "Trains the body-part classifier on labelled agex datasets");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&datasets)->multitoken (), "dataset directory, optionally @sequences (e.g. bonn@1,2,3)")
    ("out", po::value (&out), "model file to write")
    ("keyframes", po::bool_switch (&keyframes), "train on keyframes only")
    ("radius", po::value (&radius)->default_value (radius, "0.1"), "metres from a labelled tip for a positive")
    ("random-negatives", po::value (&random_negatives)->default_value (random_negatives),
     "random surface points per frame added as negatives")
    ("weak-count", po::value (&classifier_params.weak_count)->default_value (classifier_params.weak_count),
     "boosting rounds (decision stumps) per class")
    ("fragments", po::value (&classifier_params.dictionary.fragments_per_class)
                      ->default_value (classifier_params.dictionary.fragments_per_class),
     "dictionary fragments cut per class")
    ("seed", po::value (&seed)->default_value (seed), "random seed (fragments, negatives)")
    ("patch-size", po::value (&patch.size)->default_value (patch.size), "patch cells per side (<= 41)")
    ("patch-extent", po::value (&patch.extent)->default_value (patch.extent, "0.6"), "patch width, metres")
    ("patch-clamp", po::value (&patch.clamp)->default_value (patch.clamp, "0.3"), "relative depth clamp, metres");
  po::options_description baseline ("Sliding-window baseline (agex::SlidingWindowDetector)");
  baseline.add_options () ("sliding-window", po::bool_switch (&sliding_window),
                           "train the sliding-window baseline: upright patches centred on the labelled tips "
                           "against random patches of the rest of the person")
    ("window-negatives", po::value (&window_negatives)->default_value (window_negatives),
     "random person pixels per frame (farther than 1.5 radius from every tip) as negatives")
    ("jitter", po::value (&jitter)->default_value (jitter), "extra positives per tip, at random pixels near it")
    ("jitter-radius", po::value (&jitter_radius)->default_value (jitter_radius, "0.04"),
     "metres from the tip for the extra positives")
    ("window-stride", po::value (&windows.stride)->default_value (windows.stride),
     "detection: pixels between window centres (stored in the model)")
    ("window-scales", po::value (&windows.scales)->multitoken ()->default_value (windows.scales, "1"),
     "detection: window extents over --patch-extent (stored in the model)");
  po::options_description all;
  all.add (general).add (baseline).add (agex::apps::pipelineOptionsDescription (params, vector_flags));

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, po::positional_options_description ()))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, params);
    if (datasets.empty () || out.empty ())
      throw std::runtime_error ("--dataset and --out are required (see --help)");
    if (windows.stride < 1 || windows.scales.empty () ||
        std::any_of (windows.scales.begin (), windows.scales.end (), [] (float s) { return !(s > 0.f); }) ||
        window_negatives < 0 || jitter < 0)
      throw std::runtime_error ("--window-stride must be at least 1, --window-scales positive, "
                                "--window-negatives and --jitter not negative");
    if (!(radius > 0.f) || random_negatives < 0 || classifier_params.weak_count < 1 ||
        classifier_params.dictionary.fragments_per_class < 1)
      throw std::runtime_error ("--radius must be positive, --random-negatives not negative, "
                                "--weak-count and --fragments at least 1");
    if (patch.size < 3 || patch.size > 41 || !(patch.extent > 0.f) || !(patch.clamp > 0.f))
      throw std::runtime_error ("--patch-size must lie in [3, 41], --patch-extent and --patch-clamp be positive");
    if (std::filesystem::is_directory (out))
      throw std::runtime_error ("--out " + out + ": a directory, not a model file");
    // Checked before hours of training: the model must not land on what it is trained from.
    {
      agex::InputFiles read;
      for (const auto &spec : datasets)
        for (const auto &file : agex::apps::datasetFiles (agex::apps::selectDataset (spec, false).dataset))
          read.add (file);
      read.checkOutput (out);
    }
    classifier_params.dictionary.seed = seed;
    const auto start = std::chrono::steady_clock::now ();

    std::vector<agex::DepthPatch> patches;
    std::vector<int> classes;
    std::mt19937_64 rng (seed);
    nlohmann::json sources = nlohmann::json::array ();
    std::size_t frames = 0;
    for (const auto &spec : datasets)
    {
      const agex::apps::DatasetSelection selection = agex::apps::selectDataset (spec, keyframes);
      agex::apps::Progress progress ("frames of " + spec, selection.frame_ids.size ());
      for (std::size_t i = 0; i < selection.frame_ids.size (); ++i)
      {
        const auto &id = selection.frame_ids[i];
        const auto labels = selection.dataset.labelsOf (id);
        if (labels.empty ())
          continue;  // unlabelled frames say nothing about where parts are
        const auto prepared = agex::runDepthPipeline (selection.dataset.loadFrame (id), params);
        if (sliding_window)
          agex::collectWindowTrainingSamples (prepared, labels, radius, jitter, jitter_radius, window_negatives,
                                                    patch, rng, patches, classes);
        else
          agex::collectTrainingSamples (prepared, labels, radius, random_negatives, patch, rng, patches,
                                              classes);
        ++frames;
        progress.step (i + 1);
      }
      sources.push_back ({{"dataset", spec}, {"frames", selection.frame_ids.size ()}});
    }
    std::array<int, 4> counts{};
    for (const int c : classes)
      ++counts[c < 0 ? 3 : c];
    std::cout << "training on " << patches.size () << " patches from " << frames << " frames: head " << counts[0]
              << ", hand " << counts[1] << ", foot " << counts[2] << ", background " << counts[3] << "\n";

    agex::PatchClassifier classifier;
    classifier.train (patches, classes, agex::kBodyPartCount, classifier_params, [] (int done, int total) {
      std::cerr << "  boosted class " << done << "/" << total << "\n";
    });
    const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
    classifier.setPatchGeometry (patch);

    agex::DetectorSettings settings;
    settings.pipeline = params;
    if (sliding_window)
    {
      settings.kind = agex::DetectorKind::SlidingWindow;
      settings.sliding_window = windows;
    }
    std::ostringstream command;
    for (int i = 0; i < argc; ++i)
      command << (i ? " " : "") << argv[i];
    const nlohmann::json training = {{"command", command.str ()},
                            {"datasets", sources},
                            {"frames", frames},
                            {"patches", {{"head", counts[0]}, {"hand", counts[1]}, {"foot", counts[2]}, {"background", counts[3]}}},
                            {"radius_m", radius},
                            {"seconds", seconds}};
    agex::DetectorModel (std::make_shared<const agex::PatchClassifier> (std::move (classifier)), settings).save (out, training);
    std::cout << out << ": trained in " << seconds << " s\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_train: error: " << e.what () << "\n";
    return 1;
  }
}

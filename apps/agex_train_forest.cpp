// agex_train_forest: trains a per-pixel body-part forest (agex::BodyPartForestTrainer) from
// agex datasets: exact classes from part-label images, else weak ones from the labelled tips.
//   agex_train_forest --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]
// Scoring a forest per pixel: agex_eval parts.

#include <agex/apps/command_line.h>
#include <agex/apps/dataset_selection.h>
#include <agex/apps/forest_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <iostream>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  agex::DepthPipelineParams pipeline;
  agex::BodyPartForestTrainerParams params;
  agex::WeakPartLabelParams weak;
  std::vector<std::string> vector_flags, datasets;
  std::string out;
  bool keyframes = false, raw_depth = false, no_balance = false;

  po::options_description general ("agex_train_forest --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [options]\n"
                                    "Trains a per-pixel body-part forest on labelled agex datasets");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&datasets)->multitoken (), "training dataset directory, optionally @sequences")
    ("out", po::value (&out), "forest model file to write")
    ("keyframes", po::bool_switch (&keyframes), "train on keyframes only")
    ("raw-depth", po::bool_switch (&raw_depth),
     "the forest reads the frame's own depth at the body pixels, not the pipeline's denoised depth");
  po::options_description all;
  all.add (general).add (agex::apps::forestTrainerOptions (params, no_balance)).add (agex::apps::weakLabelOptions (weak))
     .add (agex::apps::pipelineOptionsDescription (pipeline, vector_flags));

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, po::positional_options_description ()))
      return 0;
    agex::apps::finishPipelineOptions (vector_flags, pipeline);
    if (datasets.empty () || out.empty ())
      throw std::runtime_error ("--dataset and --out are required (see --help; agex_eval parts scores a forest)");
    agex::apps::finishForestTrainerOptions (params, no_balance);
    weak.validate ();
    agex::InputFiles read;
    for (const auto &spec : datasets)
      read.addTree (agex::apps::selectDataset (spec, false).dataset.directory ());
    agex::apps::checkOutputPath (out, agex::apps::OutputKind::Forest, read);

    std::vector<agex::BodyPartTrainingFrame> frames;
    const nlohmann::json sources = agex::apps::collectForestTrainingFrames (datasets, keyframes, pipeline, weak,
                                                                          raw_depth, frames);
    const agex::apps::TrainedForest trained = agex::apps::trainForest (frames, params);
    nlohmann::json meta = agex::apps::forestTrainingMetadata (argc, argv, params, weak, trained);
    meta["datasets"] = sources;
    trained.forest->save (out, meta.dump ());
    std::cout << out << ": " << agex::apps::describeForest (*trained.forest) << "; trained on " << frames.size ()
              << " frames in " << trained.seconds << " s (" << params.threads << " threads)\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_train_forest: error: " << e.what () << "\n";
    return 1;
  }
}

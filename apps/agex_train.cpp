// agex_train: trains the body-part classifier from labelled agex datasets and writes one model
// file holding everything detection needs: for AGEX points (the default), for the
// sliding-window baseline (--sliding-window), or for the fused detector (--fused --forest F).
//   agex_train --dataset DIR[@SEQ,...] [--dataset ...] --out MODEL [--sliding-window | --fused --forest F]

#include <agex/apps/train_flags.h>
#include <agex/apps/training_runs.h>

#include <chrono>
#include <iostream>
#include <sstream>

int
main (int argc, char **argv)
{
  agex::apps::TrainFlags flags;
  try
  {
    if (!agex::apps::parseTrainFlags (argc, argv, flags))
      return 0;
    const auto start = std::chrono::steady_clock::now ();
    std::vector<agex::DepthPatch> patches;
    std::vector<std::vector<float>> auxiliary;
    std::vector<int> classes;
    const nlohmann::json sources = agex::apps::collectTrainingExamples (flags.datasets, flags.choice, flags.settings,
                                                                        flags.patch, patches, auxiliary, classes);
    std::ostringstream command;
    for (int i = 0; i < argc; ++i)
      command << (i ? " " : "") << argv[i];
    if (!flags.cascade_for.empty ())
    {
      // The model's own training record stays; the cascade's fit is added beside it.
      const agex::DetectorModel base = agex::DetectorModel::load (flags.cascade_for);
      const agex::DetectorModel model = agex::apps::withFittedCascade (
          base, flags.cascade_for, flags.settings, patches, auxiliary, classes, flags.classifier_params);
      const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
      nlohmann::json training = base.training ();
      training["cascade_fit"] = {{"command", command.str ()}, {"datasets", sources}, {"patches", patches.size ()},
                                 {"seconds", seconds}};
      model.save (flags.out, training);
      std::cout << flags.out << ": " << flags.cascade_for << " with its soft cascade fitted in " << seconds << " s\n";
      return 0;
    }
    const agex::DetectorModel model = agex::apps::trainDetector (patches, auxiliary, classes, flags.classifier_params,
                                                                 flags.patch, flags.settings);
    const double seconds = std::chrono::duration<double> (std::chrono::steady_clock::now () - start).count ();
    model.save (flags.out, {{"command", command.str ()}, {"datasets", sources}, {"patches", patches.size ()},
                            {"radius_m", flags.choice.radius}, {"seconds", seconds}});
    std::cout << flags.out << ": trained in " << seconds << " s\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_train: error: " << e.what () << "\n";
    return 1;
  }
}

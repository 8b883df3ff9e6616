// agex_synth: synthetic labelled depth frames of people moving as in real motion
// capture, written as an agex dataset (doc/synthetic.md). The same seed gives the
// same bytes.

#include <agex/apps/command_line.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/synth_flags.h>
#include <agex/io/atomic_file.h>
#include <agex/simulation/synthetic_scene.h>

#include <algorithm>
#include <iostream>

int
main (int argc, char **argv)
{
  agex::apps::SynthFlags flags;
  try
  {
    if (!agex::apps::parseSynthFlags (argc, argv, flags))
      return 0;
    std::vector<std::string> inputs = flags.options.motion_files;
    if (!flags.options.body_mesh.empty ())
      inputs.push_back (flags.options.body_mesh);
    agex::apps::checkOutputPath (flags.output, agex::apps::OutputKind::Dataset, agex::InputFiles (inputs), flags.force);

    const agex::SynthGenerator generator (flags.options);
    for (const auto &clip : generator.clips ())
      std::cout << clip.motion.path () << ": " << clip.motion.frameCount () << " frames, " << clip.scale
                << " m/unit" << (clip.scale_auto ? " (auto)" : "") << ", rest height "
                << agex::restStandingHeight (clip) << " m\n";
    agex::apps::Progress progress ("rendered", static_cast<std::size_t> (flags.frames));
    const agex::SynthRunStats stats =
        agex::writeSyntheticDataset (generator, flags.frames, flags.output, flags.force,
                                     [&] (int done, int) { progress.step (static_cast<std::size_t> (done)); });

    std::cout << flags.output << ": " << stats.frames << " " << flags.sensor << " frames ("
              << generator.sensor ().width << "x" << generator.sensor ().height << "), " << stats.visible_labels
              << " of " << stats.labels << " labels visible\n"
              << "  render " << stats.render_ms / stats.frames << " ms/frame, write "
              << stats.write_ms / stats.frames << " ms/frame: "
              << 1000.0 * stats.frames / std::max (1e-9, stats.render_ms + stats.write_ms) << " frames/s on one thread\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_synth: error: " << e.what () << "\n";
    return 1;
  }
}

// agex_synth: synthetic labelled depth frames of people moving as in real motion
// capture, written as an agex dataset (doc/synthetic.md). The same seed gives the
// same bytes.

#include <agex/apps/command_line.h>
#include <agex/apps/output.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/synth_flags.h>
#include <agex/io/atomic_file.h>
#include <agex/simulation/pose_bank.h>
#include <agex/simulation/synthetic_scene.h>

#include <algorithm>
#include <cstdio>

#include <iostream>

int
main (int argc, char **argv)
{
  agex::apps::SynthFlags flags;
  try
  {
    if (!agex::apps::parseSynthFlags (argc, argv, flags))
      return 0;
    if (!flags.pose_report.empty ())
    {
      // The picture may replace only an earlier PNG of agex's, never an input.
      std::vector<std::string> report_inputs = flags.options.motion_files;
      report_inputs.insert (report_inputs.end (), flags.options.pose_dirs.begin (), flags.options.pose_dirs.end ());
      agex::apps::checkOutputPath (flags.pose_report, agex::apps::OutputKind::Png, agex::InputFiles (report_inputs),
                                   flags.force);
      const agex::PoseBank bank = agex::poseBankOf (flags.options);
      for (const auto &s : bank.sources ())
        std::cout << "pose bank: " << s.name << ": " << s.raw << " poses read, " << s.dropped << " dropped, " << s.kept
                  << " kept\n";
      std::cout << "pose bank: " << bank.size () << " poses after thinning to " << flags.options.thin_poses << " m\n";
      for (const auto &h : bank.handSpread ())
      {
        char line[320];
        std::snprintf (line, sizeof line,
                       "hands %s: n=%d mean (out %.2f, up %.2f, fwd %.2f) sd (%.2f, %.2f, %.2f) above head %.1f%% "
                       "forward>0.35 %.1f%% behind %.1f%% across %.1f%%\n",
                       h.source.c_str (), h.hands, h.mean.x (), h.mean.y (), h.mean.z (), h.sd.x (), h.sd.y (), h.sd.z (),
                       100 * h.above_head, 100 * h.forward, 100 * h.behind, 100 * h.across);
        std::cout << line;
      }
      agex::apps::writePng (flags.pose_report, bank.spreadImage ());
      std::cout << flags.pose_report << ": hand positions written\n";
      if (flags.report_only)
        return 0;
    }
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

// agex_convert: turns recorded data into agex datasets (doc/dataset.md).
//   agex_convert bonn --input ../shared/data/bonn --output DIR [--view full|portrait] [--sequences 1,2]
//   agex_convert u16  --input FILE|DIR... --output DIR [--width W --height H]
//   agex_convert pcd  --input FILE|DIR... --output DIR

#include <agex/apps/command_line.h>
#include <agex/apps/convert_flags.h>
#include <agex/apps/output_guard.h>
#include <agex/io/bonn.h>
#include <agex/io/dataset_conversion.h>

#include <filesystem>
#include <iostream>

int
main (int argc, char **argv)
{
  agex::apps::ConvertFlags flags;
  try
  {
    if (!agex::apps::parseConvertFlags (argc, argv, flags))
      return 0;
    using agex::apps::OutputKind;
    if (flags.mode == "bonn")
    {
      if (flags.inputs.size () != 1)
        throw std::runtime_error ("bonn takes one --input: the Bonn data directory");
      const agex::BonnConversionParams params = agex::apps::bonnConversionParams (flags);
      const agex::BonnConversion conversion = agex::planBonnConversion (flags.inputs[0], params);
      agex::apps::checkOutputPath (flags.output, OutputKind::Dataset, agex::InputFiles (conversion.inputFiles ()),
                                   flags.force);
      agex::apps::Progress progress ("converted", conversion.frames.size ());
      const agex::BonnConversionStats stats = agex::writeBonnDataset (
          conversion, flags.output, flags.force, [&] (std::size_t done, std::size_t) { progress.step (done); });
      std::cout << flags.output << ": " << stats.frames << " frames, " << stats.lifted << " labels lifted to 3D, "
                << stats.unlifted << " without depth near the labelled pixel (marked invisible)\n";
      return 0;
    }
    if (flags.mode == "u16" || flags.mode == "pcd")
    {
      const agex::FrameFilesConversion conversion = agex::planFrameFilesConversion (
          flags.mode, flags.inputs, std::filesystem::path (flags.output).filename ().string (), flags.sensor,
          flags.frame_options);
      agex::apps::checkOutputPath (flags.output, OutputKind::Dataset, agex::InputFiles (conversion.inputFiles ()),
                                   flags.force);
      agex::apps::Progress progress ("converted", conversion.files.size ());
      const std::size_t frames =
          agex::writeFrameFilesDataset (conversion, flags.frame_options, flags.output, flags.force,
                                        [&] (std::size_t done, std::size_t) { progress.step (done); });
      std::cout << flags.output << ": " << frames << " frames (no labels)\n";
      return 0;
    }
    throw std::runtime_error ("unknown mode '" + flags.mode + "' (expected bonn, u16 or pcd)");
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_convert: error: " << e.what () << "\n";
    return 1;
  }
}

#include <agex/apps/convert_flags.h>

#include <agex/apps/command_line.h>
#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <sstream>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
bool
parseConvertFlags (int argc, char **argv, ConvertFlags &flags)
{
  po::options_description general ("agex_convert bonn|u16|pcd --input PATH... --output DIR [options]\n"
                                    "Converts recorded frames into an agex dataset (doc/dataset.md)");
  general.add_options () ("help,h", "show this help") ("mode", po::value (&flags.mode), "bonn, u16 or pcd")
    ("input", po::value (&flags.inputs)->multitoken (), "bonn: the Bonn data directory; u16/pcd: files or directories")
    ("output", po::value (&flags.output), "dataset directory to create")
    ("force", po::bool_switch (&flags.force), "replace an existing output dataset")
    ("view", po::value (&flags.view)->default_value (flags.view), "bonn: portrait (144x176, as the source) or full (640x480)")
    ("sequences", po::value (&flags.sequences), "bonn: comma-separated sequences (default: all)")
    ("label-radius", po::value (&flags.label_radius)->default_value (flags.label_radius),
     "bonn: pixels searched around a label for its surface point")
    ("label-depth-band", po::value (&flags.depth_band)->default_value (flags.depth_band, "0.05"),
     "bonn: metres behind the nearest depth in that window still counted as foreground")
    ("sensor", po::value (&flags.sensor)->default_value (flags.sensor), "u16/pcd: sensor name recorded in dataset.json");
  po::options_description all;
  all.add (general).add (frameOptionsDescription (flags.frame_options));
  po::positional_options_description positional;
  positional.add ("mode", 1);

  if (!parseCommandLine (argc, argv, all, positional))
    return false;
  if (flags.output.empty () || flags.inputs.empty ())
    throw std::runtime_error ("--input and --output are required (see --help)");
  if (flags.label_radius < 0 || !(flags.depth_band > 0.f))
    throw std::runtime_error ("--label-radius must be >= 0 and --label-depth-band > 0");
  return true;
}

BonnConversionParams
bonnConversionParams (const ConvertFlags &flags)
{
  if (flags.view != "full" && flags.view != "portrait")
    throw std::runtime_error ("--view must be full or portrait, not '" + flags.view + "'");
  BonnConversionParams params;
  params.portrait = flags.view == "portrait";
  std::stringstream in (flags.sequences);
  for (std::string item; std::getline (in, item, ',');)
    if (!item.empty ())
      params.sequences.push_back (item);
  params.frame_options = flags.frame_options;
  params.label_radius = flags.label_radius;
  params.depth_band = flags.depth_band;
  return params;
}
}  // namespace apps
}  // namespace agex

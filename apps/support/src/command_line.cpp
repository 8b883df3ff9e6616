#include <agex/apps/command_line.h>

#include <boost/program_options/parsers.hpp>
#include <boost/program_options/variables_map.hpp>

#include <iostream>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
bool
parseCommandLine (int argc, char **argv, const po::options_description &options,
                  const po::positional_options_description &positional)
{
  po::variables_map vm;
  po::store (po::command_line_parser (argc, argv).options (options).positional (positional).run (), vm);
  if (vm.count ("help"))
  {
    std::cout << options << "\n";
    return false;
  }
  po::notify (vm);
  return true;
}
}  // namespace apps
}  // namespace agex

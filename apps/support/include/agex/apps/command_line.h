#pragma once

#include <boost/program_options/options_description.hpp>
#include <boost/program_options/positional_options.hpp>

namespace agex
{
namespace apps
{
/** \brief Parses the command line into the variables bound in options and runs
  * their notifiers. Prints the options and returns false when --help was given.
  * \throws boost::program_options::error on an unknown or malformed flag */
bool parseCommandLine (int argc, char **argv, const boost::program_options::options_description &options,
                       const boost::program_options::positional_options_description &positional);
}  // namespace apps
}  // namespace agex

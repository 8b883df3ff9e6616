// A main for the fuzz targets in builds without libFuzzer (every build): runs
// LLVMFuzzerTestOneInput on each file given, or on each file in each directory given,
// so that the seed corpora and the kept crashers (regressions/) are checked by ctest
// with the ordinary compiler, and under AGEX_SANITIZE with the sanitizers.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size);

int
main (int argc, char **argv)
{
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i)
  {
    if (fs::is_directory (argv[i]))
    {
      for (const auto &entry : fs::directory_iterator (argv[i]))
        if (entry.is_regular_file () && entry.path ().filename () != "README.md")
          inputs.push_back (entry.path ());
    }
    else if (fs::is_regular_file (argv[i]))
      inputs.emplace_back (argv[i]);
    else
    {
      std::fprintf (stderr, "%s: no such file or directory\n", argv[i]);
      return 2;
    }
  }
  std::sort (inputs.begin (), inputs.end ());
  for (const auto &path : inputs)
  {
    std::ifstream in (path, std::ios::binary);
    const std::vector<char> bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
    std::fprintf (stderr, "%s (%zu bytes)\n", path.c_str (), bytes.size ());
    LLVMFuzzerTestOneInput (reinterpret_cast<const std::uint8_t *> (bytes.data ()), bytes.size ());
  }
  std::printf ("replayed %zu inputs\n", inputs.size ());
  return inputs.empty () ? 1 : 0;
}

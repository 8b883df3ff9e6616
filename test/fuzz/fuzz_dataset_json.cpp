// Fuzz target: agex::Dataset::read on a directory whose dataset.json is the input
// (labels.csv is a header only). Frame files for the first ids the input lists are
// created empty, so that the reader gets past its "frame missing" check. Any input must
// give a dataset or an agex::DatasetError.
#include "fuzz_support.h"

#include <agex/io/dataset.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  namespace fs = std::filesystem;
  const fs::path dir = fs::path (agex::fuzz::scratchDirectory ()) / "dataset";
  std::error_code ec;
  fs::remove_all (dir, ec);
  fs::create_directories (dir / "frames");
  {
    std::ofstream json (dir / "dataset.json", std::ios::binary);
    json.write (reinterpret_cast<const char *> (data), static_cast<std::streamsize> (size));
    std::ofstream labels (dir / "labels.csv");
    labels << agex::formatLabelsCsv ({});
  }
  const auto doc = nlohmann::json::parse (data, data + size, nullptr, false);
  if (doc.is_object () && doc.contains ("frames") && doc["frames"].is_array ())
  {
    int created = 0;
    for (const auto &f : doc["frames"])
      if (f.is_object () && f.contains ("id") && f["id"].is_string () && ++created <= 8)
      {
        const std::string id = f["id"].get<std::string> ();
        if (!id.empty () && id.size () < 64 && id.find ('/') == std::string::npos && id != "." && id != "..")
          std::ofstream (dir / "frames" / (id + ".pcd"));
      }
  }
  try
  {
    const agex::Dataset dataset = agex::Dataset::read (dir.string ());
    if (dataset.info ().width <= 0 || dataset.info ().height <= 0)
      __builtin_trap ();
  }
  catch (const agex::DatasetError &)
  {
  }
  return 0;
}

#include <agex/apps/output_guard.h>

#include <agex/io/dataset.h>
#include <agex/io/input_file.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace agex
{
namespace apps
{
namespace
{
constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
const std::string kMarkKeyword = std::string ("Software\0agex", 13);

std::uint32_t
crc32 (const std::string &bytes)
{
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n)
    {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k)
        c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xffffffffu;
  for (const char b : bytes)
    c = table[(c ^ static_cast<unsigned char> (b)) & 0xff] ^ (c >> 8);
  return c ^ 0xffffffffu;
}

void
appendBigEndian (std::string &out, std::uint32_t v)
{
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back (static_cast<char> ((v >> shift) & 0xff));
}

std::uint32_t
readBigEndian (const std::string &bytes, std::size_t at)
{
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i)
    v = (v << 8) | static_cast<unsigned char> (bytes[at + i]);
  return v;
}

bool
hasPngSignature (const std::string &bytes)
{
  return bytes.size () >= 8 && std::equal (kPngSignature, kPngSignature + 8, bytes.begin (),
                                           [] (unsigned char a, char b) { return a == static_cast<unsigned char> (b); });
}

/** The first max bytes of a regular file. */
std::string
readHead (const std::string &path, std::size_t max)
{
  std::ifstream in (path, std::ios::binary);
  std::string bytes (max, '\0');
  in.read (bytes.data (), static_cast<std::streamsize> (max));
  bytes.resize (static_cast<std::size_t> (in.gcount ()));
  return bytes;
}

[[noreturn]] void
refuse (const std::string &path, const std::string &why)
{
  throw std::runtime_error (path + ": " + why);
}

/** Why the file is not one frame's JSON document (writeJson: pretty-printed), e.g. because it
  * is a JSON-lines file; "" if it is one. */
std::string
notAFrameDocument (const std::string &path)
{
  constexpr std::size_t kMax = std::size_t (64) << 20;
  const std::string bytes = readHead (path, kMax + 1);
  if (bytes.size () > kMax)
    return "exists and is larger than any JSON document agex writes";
  // A JSON-lines file's first line is a whole result; a document's first line is "{".
  const auto first = nlohmann::json::parse (bytes.substr (0, bytes.find ('\n')), nullptr, false);
  if (first.is_object () && first.contains ("frame"))
    return "is a JSON-lines results file of a run over several frames, which this frame's document would replace";
  const auto doc = nlohmann::json::parse (bytes, nullptr, false);
  if (doc.is_discarded () || !doc.is_object () || !doc.contains ("frame"))
    return "exists and is not a JSON document of a frame written by agex";
  return "";
}
}  // namespace

std::string
markAgexPng (const std::string &png)
{
  // Signature, then the IHDR chunk (length 13): 8 + 4 + 4 + 13 + 4 bytes.
  constexpr std::size_t kAfterHeader = 33;
  if (!hasPngSignature (png) || png.size () < kAfterHeader || png.compare (12, 4, "IHDR") != 0 ||
      readBigEndian (png, 8) != 13)
    return png;
  std::string chunk;
  appendBigEndian (chunk, static_cast<std::uint32_t> (kMarkKeyword.size ()));
  const std::string body = "tEXt" + kMarkKeyword;
  chunk += body;
  appendBigEndian (chunk, crc32 (body));
  return png.substr (0, kAfterHeader) + chunk + png.substr (kAfterHeader);
}

bool
isAgexPng (const std::string &bytes)
{
  if (!hasPngSignature (bytes))
    return false;
  // Walk the chunks before the image data; the mark comes right after the header.
  for (std::size_t at = 8; at + 12 <= bytes.size ();)
  {
    const std::uint32_t length = readBigEndian (bytes, at);
    const std::string type = bytes.substr (at + 4, 4);
    if (type == "IDAT" || type == "IEND" || length > bytes.size ())
      return false;
    if (type == "tEXt" && length == kMarkKeyword.size () && at + 8 + length <= bytes.size () &&
        bytes.compare (at + 8, length, kMarkKeyword) == 0)
      return true;
    at += 12 + static_cast<std::size_t> (length);
  }
  return false;
}

void
checkOutputPath (const std::string &path, OutputKind kind, const InputFiles &inputs, bool force)
{
  inputs.checkOutput (path);
  std::error_code ec;
  const fs::file_status status = fs::symlink_status (path, ec);
  if (ec || !fs::exists (status))
    return;
  if (kind == OutputKind::Dataset)
  {
    const std::string problem = datasetReplaceProblem (path);
    if (!problem.empty ())
      refuse (path, problem + "; --force replaces only an earlier agex dataset: choose another path");
    if (!force)
      refuse (path, "already exists; pass --force to replace it");
    return;
  }
  const std::string not_regular = notARegularFile (path);
  if (!not_regular.empty ())
    refuse (path, not_regular + "; choose another path");
  if (fs::file_size (path, ec) == 0 && !ec)
    return;  // nothing to lose
  switch (kind)
  {
  case OutputKind::JsonDocument:
  {
    const std::string why = notAFrameDocument (path);
    if (!why.empty ())
      refuse (path, why + "; choose another path or remove it");
    return;
  }
  case OutputKind::Png:
    if (!isAgexPng (readHead (path, 1 << 16)))
      refuse (path, "exists and is not a PNG written by agex; choose another path or remove it");
    return;
  case OutputKind::Forest:
    if (readHead (path, 8) != "AGEXFRST")
      refuse (path, "exists and is not an agex forest file; choose another path or remove it");
    return;
  case OutputKind::Json:
  {
    std::ifstream in (path, std::ios::binary);
    bool object = false;
    try
    {
      object = nlohmann::json::parse (in).is_object ();
    }
    catch (const std::exception &)
    {
    }
    if (!object)
      refuse (path, "exists and is not a JSON report; choose another path or remove it");
    return;
  }
  case OutputKind::JsonLines:
  case OutputKind::Dataset:
    return;
  }
}
}  // namespace apps
}  // namespace agex

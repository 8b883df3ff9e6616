#include <agex/apps/output_guard.h>

#include <agex/io/dataset.h>
#include <agex/io/input_file.h>

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <iostream>
#include <set>
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

namespace
{
/** Why the file is not a JSON object, "" if it is one (parsed into doc). */
std::string
notAJsonObject (const std::string &path, nlohmann::json &doc)
{
  constexpr std::size_t kMax = std::size_t (256) << 20;
  const std::string bytes = readHead (path, kMax + 1);
  if (bytes.size () > kMax)
    return "exists and is larger than any JSON report agex writes";
  doc = nlohmann::json::parse (bytes, nullptr, false);
  return doc.is_object () ? "" : "exists and is not a JSON object";
}

std::string
missingKey (const nlohmann::json &object, const std::vector<std::string> &keys)
{
  for (const std::string &key : keys)
    if (!object.contains (key))
      return key;
  return "";
}

/** The recogniser of each kind of file output (Dataset has rules of its own). */
OutputRecogniser
recogniserOf (OutputKind kind)
{
  switch (kind)
  {
  case OutputKind::JsonDocument:
    return notAFrameDocument;
  case OutputKind::Png:
    return [] (const std::string &path) {
      return isAgexPng (readHead (path, 1 << 16)) ? "" : "exists and is not a PNG written by agex";
    };
  case OutputKind::Forest:
    return [] (const std::string &path) {
      return readHead (path, 8) == "AGEXFRST" ? "" : "exists and is not an agex forest file";
    };
  case OutputKind::Json:
    return jsonReportWith ({});
  case OutputKind::Model:
    return [] (const std::string &path) {
      // The format line comes right after the YAML header (DetectorModel::write).
      return readHead (path, 256).find ("\nformat: agex-model\n") != std::string::npos ? "" : "exists and is not an agex model";
    };
  case OutputKind::ImglabXml:
    return [] (const std::string &path) {
      const std::string head = readHead (path, 4096);
      return head.find ("<dataset>") != std::string::npos && head.find ("<comment>agex_annotate") != std::string::npos
                 ? ""
                 : "exists and is not an imglab dataset written by agex_annotate";
    };
  case OutputKind::JsonLines:  // ResultsFile reads the lines back and refuses what is not a result
  case OutputKind::Dataset:
    break;
  }
  return [] (const std::string &) { return std::string (); };
}
}  // namespace

OutputRecogniser
jsonReportWith (const std::vector<std::string> &keys)
{
  return [keys] (const std::string &path) -> std::string {
    nlohmann::json doc;
    const std::string why = notAJsonObject (path, doc);
    if (!why.empty ())
      return why + ", not a JSON report of agex";
    const std::string missing = missingKey (doc, keys);
    return missing.empty () ? "" : "exists and is a JSON object without \"" + missing + "\", not a report of this app";
  };
}

OutputRecogniser
jsonLinesWith (const std::vector<std::string> &keys)
{
  return [keys] (const std::string &path) -> std::string {
    constexpr std::size_t kMax = std::size_t (1) << 30;
    std::ifstream in (path, std::ios::binary);
    std::string line;
    std::size_t n = 0, bytes = 0;
    while (std::getline (in, line))
    {
      ++n;
      bytes += line.size () + 1;
      if (bytes > kMax)
        return "exists and is larger than any JSON-lines file agex writes";
      if (line.empty ())
        continue;
      const auto doc = nlohmann::json::parse (line, nullptr, false);
      if (!doc.is_object () || !missingKey (doc, keys).empty ())
        return "exists and its line " + std::to_string (n) + " is not a JSON line of this app";
    }
    return "";
  };
}

void
checkOutputPath (const std::string &path, const std::string &what, const OutputRecogniser &recognise,
                 const InputFiles &inputs)
{
  inputs.checkOutput (path);
  std::error_code ec;
  const fs::file_status status = fs::symlink_status (path, ec);
  if (ec || !fs::exists (status))
    return;
  const std::string not_regular = notARegularFile (path);
  if (!not_regular.empty ())
    refuse (path, not_regular + "; choose another path");
  if (fs::file_size (path, ec) == 0 && !ec)
    return;  // nothing to lose
  const std::string why = recognise (path);
  if (!why.empty ())
    refuse (path, why + (what.empty () ? "" : " (" + what + ")") + "; choose another path or remove it");
}

void
checkOutputPath (const std::string &path, OutputKind kind, const InputFiles &inputs, bool force)
{
  if (kind != OutputKind::Dataset)
    return checkOutputPath (path, "", recogniserOf (kind), inputs);
  inputs.checkOutput (path);
  std::error_code ec;
  if (!fs::exists (fs::symlink_status (path, ec)) || ec)
    return;
  const std::string problem = datasetReplaceProblem (path);
  if (!problem.empty ())
    refuse (path, problem + "; --force replaces only an earlier agex dataset: choose another path");
  if (!force)
    refuse (path, "already exists; pass --force to replace it");
}

void
checkPngsInFolder (const std::vector<std::string> &pngs, const InputFiles &inputs)
{
  for (const std::string &png : pngs)
  {
    const fs::path folder = fs::path (png).parent_path ();
    std::error_code ec;
    if (!folder.empty () && fs::exists (folder, ec) && !fs::is_directory (folder, ec))
      refuse (folder.string (), "is not a folder; choose another folder for the PNGs");
    checkOutputPath (png, OutputKind::Png, inputs);
  }
}

OutputSetClaim::OutputSetClaim (const std::vector<std::string> &paths)
{
  std::set<fs::path> folders;
  for (const std::string &path : paths)
  {
    if (path.empty ())
      continue;
    std::error_code ec;
    const fs::path parent = fs::path (path).parent_path ();
    const fs::path folder = fs::weakly_canonical (parent.empty () ? fs::path (".") : parent, ec);
    if (!ec)
      folders.insert (folder);
  }
  for (const fs::path &folder : folders)  // std::set: one order for every run, so no deadlock
  {
    const int fd = ::open (folder.c_str (), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
      continue;
    int locked;
    while ((locked = ::flock (fd, LOCK_EX)) != 0 && errno == EINTR)
    {
    }
    if (locked != 0)
    {
      // Some network file systems refuse flock on a folder: the outputs are still written
      // atomically, one by one, but say so rather than claim what was not held.
      std::cerr << "warning: " << folder.string () << ": cannot lock the folder (" << std::strerror (errno)
                << "); outputs written there by two runs at once may mix\n";
      ::close (fd);
      continue;
    }
    fds_.push_back (fd);
  }
}

OutputSetClaim::~OutputSetClaim ()
{
  for (const int fd : fds_)
    ::close (fd);  // closing releases the lock
}
}  // namespace apps
}  // namespace agex

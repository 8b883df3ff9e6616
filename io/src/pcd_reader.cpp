#include <agex/io/pcd_reader.h>
#include <agex/io/input_file.h>

#include <pcl/common/io.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <string_view>
#include <vector>

namespace agex
{
namespace
{
[[noreturn]] void
fail (const std::string &path, const std::string &problem)
{
  throw FrameError (path + ": " + problem);
}

/** A piece of the file fit for an error message: at most 40 characters, unprintable ones as '?'. */
std::string
shown (std::string_view text)
{
  std::string out (text.substr (0, 40));
  for (char &c : out)
    if (static_cast<unsigned char> (c) < 0x20 || static_cast<unsigned char> (c) > 0x7e)
      c = '?';
  return out;
}

std::vector<std::string_view>
splitWords (std::string_view line)
{
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size ())
  {
    while (i < line.size () && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
      ++i;
    const std::size_t start = i;
    while (i < line.size () && line[i] != ' ' && line[i] != '\t' && line[i] != '\r')
      ++i;
    if (i > start)
      words.push_back (line.substr (start, i - start));
  }
  return words;
}

/** The PCD header is read from at most this many bytes (PCL's own are a few hundred). */
constexpr std::size_t kMaxHeaderBytes = 1 << 16;

struct PcdHeader
{
  std::vector<std::string_view> names, sizes, types, counts;
  std::uint64_t width = 0, height = 0, points = 0;
  std::string_view data;
  bool has_count = false;
  std::size_t data_offset = 0;  ///< first byte after the DATA line
};

std::uint64_t
wholeNumber (const std::string &path, const std::string &keyword, std::string_view token)
{
  std::uint64_t value = 0;
  const auto [end, ec] = std::from_chars (token.data (), token.data () + token.size (), value);
  if (token.empty () || token.find_first_not_of ("0123456789") != std::string_view::npos ||
      end != token.data () + token.size ())
    fail (path, "PCD " + keyword + " line holds '" + shown (token.substr (0, 20)) + "', not a whole number");
  if (ec == std::errc::result_out_of_range)
    fail (path, "PCD " + keyword + " line holds " + shown (token) + ", a number too large");
  return value;
}

/** Parses the header from the start of the file. Each keyword at most once and exactly
  * spelled: PCL matches them by prefix and keeps pointers into what a repeated line replaced. */
PcdHeader
parseHeader (const std::string &path, std::string_view text, bool whole_file)
{
  static const char *const kKeywords[] = {"VERSION", "FIELDS",    "SIZE",   "TYPE", "COUNT",
                                          "WIDTH",   "HEIGHT",    "POINTS", "DATA", "VIEWPOINT"};
  PcdHeader header;
  std::map<std::string_view, bool> seen;
  std::size_t pos = 0;
  while (true)
  {
    // The header must end inside text; a DATA line cut off by the end of text does not count.
    if (pos >= text.size () || (!whole_file && text.find ('\n', pos) == std::string_view::npos))
      fail (path, !whole_file
                      ? "not a readable PCD file (no DATA line in its first " + std::to_string (kMaxHeaderBytes) + " bytes)"
                      : "not a readable PCD file (bad or missing header)");
    std::size_t end = text.find ('\n', pos);
    const bool last = end == std::string_view::npos;
    if (last)
      end = text.size ();
    const std::string_view line = text.substr (pos, end - pos);
    pos = last ? end : end + 1;
    const std::vector<std::string_view> words = splitWords (line);
    if (words.empty () || words[0][0] == '#')
      continue;
    const std::string_view key = words[0] == "COLUMNS" ? std::string_view ("FIELDS") : words[0];
    if (std::none_of (std::begin (kKeywords), std::end (kKeywords), [&] (const char *k) { return key == k; }))
      fail (path, "PCD header line '" + shown (line) + "' is damaged");
    if (seen[key])
      fail (path, "PCD header has more than one " + std::string (key) + " line (damaged header)");
    seen[key] = true;
    const std::vector<std::string_view> values (words.begin () + 1, words.end ());
    const std::string keyword (key);
    auto single = [&] () {
      if (values.size () != 1)
        fail (path, "PCD " + keyword + " line needs one value, has " + std::to_string (values.size ()));
      return values[0];
    };
    if (key == "VERSION")
    {
      static const char *const kVersions[] = {"0.7", ".7", "0.6", ".6", "0.5", ".5"};
      const std::string_view version = single ();
      if (std::none_of (std::begin (kVersions), std::end (kVersions), [&] (const char *v) { return version == v; }))
        fail (path, "PCD VERSION " + shown (version) + " is not one agex reads (0.5 to 0.7)");
    }
    else if (key == "FIELDS")
      header.names = values;
    else if (key == "SIZE" || key == "COUNT")
    {
      for (std::string_view token : values)
        wholeNumber (path, keyword, token);
      (key == "SIZE" ? header.sizes : header.counts) = values;
      header.has_count = header.has_count || key == "COUNT";
    }
    else if (key == "TYPE")
      header.types = values;
    else if (key == "WIDTH")
      header.width = wholeNumber (path, keyword, single ());
    else if (key == "HEIGHT")
      header.height = wholeNumber (path, keyword, single ());
    else if (key == "POINTS")
      header.points = wholeNumber (path, keyword, single ());
    else if (key == "VIEWPOINT")
    {
      if (values.size () != 7)
        fail (path, "PCD VIEWPOINT line needs 7 numbers, has " + std::to_string (values.size ()));
    }
    else  // DATA ends the header
    {
      header.data = single ();
      header.data_offset = pos;
      break;
    }
  }
  for (const char *required : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS"})
    if (!seen[required])
      fail (path, std::string ("PCD header has no ") + required + " line (bad or missing header)");
  if (header.data != "ascii" && header.data != "binary" && header.data != "binary_compressed")
    fail (path, "PCD DATA line says '" + shown (header.data) + "'; agex reads ascii, binary and binary_compressed");
  return header;
}

/** The TYPE and SIZE pairs of PCD fields and the PCL datatype of each. */
struct PcdType
{
  char type;
  std::uint64_t size;
  std::uint8_t datatype;
};
constexpr PcdType kPcdTypes[] = {
    {'F', 4, pcl::PCLPointField::FLOAT32}, {'F', 8, pcl::PCLPointField::FLOAT64}, {'I', 1, pcl::PCLPointField::INT8},
    {'I', 2, pcl::PCLPointField::INT16},   {'I', 4, pcl::PCLPointField::INT32},   {'I', 8, pcl::PCLPointField::INT64},
    {'U', 1, pcl::PCLPointField::UINT8},   {'U', 2, pcl::PCLPointField::UINT16},  {'U', 4, pcl::PCLPointField::UINT32},
    {'U', 8, pcl::PCLPointField::UINT64}, {'B', 1, pcl::PCLPointField::BOOL}};

/** The datatype of a TYPE and SIZE, 0 for a pair PCD does not have. */
std::uint8_t
fieldType (std::string_view type, std::uint64_t size)
{
  // PCL upper-cases the letter before reading it.
  for (const PcdType &t : kPcdTypes)
    if (type.size () == 1 && std::toupper (static_cast<unsigned char> (type[0])) == t.type && size == t.size)
      return t.datatype;
  return 0;
}

/** "F 4", "U 1", ...: a datatype as its PCD TYPE and SIZE. */
std::string
typeName (std::uint8_t datatype)
{
  for (const PcdType &t : kPcdTypes)
    if (t.datatype == datatype)
      return std::string (1, t.type) + " " + std::to_string (t.size);
  return "?";
}

/** Fields, offsets and sizes of the cloud from the header; every number checked. */
void
layOutCloud (const std::string &path, const PcdHeader &header, pcl::PCLPointCloud2 &cloud)
{
  const std::size_t n = header.names.size ();
  // Every field needs its SIZE and TYPE (and COUNT, when given).
  if (n == 0 || header.sizes.size () != n || header.types.size () != n || (header.has_count && header.counts.size () != n))
    fail (path, "PCD header has " + std::to_string (n) + " fields but " + std::to_string (header.sizes.size ()) +
                    " sizes, " + std::to_string (header.types.size ()) + " types and " +
                    std::to_string (header.counts.size ()) + " counts (damaged FIELDS, SIZE, TYPE or COUNT line)");
  std::uint64_t point_step = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::string name (header.names[i]);
    for (std::size_t j = 0; j < i; ++j)
      if (name != "_" && header.names[j] == header.names[i])  // "_" is PCL's padding
        fail (path, "PCD field '" + shown (name) + "' appears twice (damaged FIELDS line)");
    const std::uint64_t size = wholeNumber (path, "SIZE", header.sizes[i]);
    const std::uint64_t count = header.has_count ? wholeNumber (path, "COUNT", header.counts[i]) : 1;
    const std::uint8_t type = fieldType (header.types[i], size);
    if (type == 0)
      fail (path, "PCD field '" + shown (name) + "' has TYPE " + shown (header.types[i]) + " and SIZE " +
                      std::to_string (size) + " (damaged SIZE or TYPE line)");
    if (count == 0 || count > kMaxPcdPointBytes || point_step + size * count > kMaxPcdPointBytes)
      fail (path, "PCD field '" + shown (name) + "' (COUNT " + std::to_string (count) +
                      ") makes a point larger than the " + std::to_string (kMaxPcdPointBytes) +
                      " bytes agex reads (damaged COUNT line)");
    pcl::PCLPointField field;
    field.name = name;
    field.offset = static_cast<std::uint32_t> (point_step);
    field.datatype = type;
    field.count = static_cast<std::uint32_t> (count);
    cloud.fields.push_back (field);
    point_step += size * count;
  }
  checkFrameSize (path, header.width, header.height);
  if (header.points != header.width * header.height)
    fail (path, "PCD header says POINTS " + std::to_string (header.points) + " but WIDTH x HEIGHT is " +
                    std::to_string (header.width) + "x" + std::to_string (header.height) + " (damaged header)");
  if (header.points * point_step > kMaxPcdDataBytes)
    fail (path, "PCD data of " + std::to_string (header.points * point_step) + " bytes is more than the " +
                    std::to_string (kMaxPcdDataBytes) + " agex reads");
  cloud.width = static_cast<std::uint32_t> (header.width);
  cloud.height = static_cast<std::uint32_t> (header.height);
  cloud.point_step = static_cast<std::uint32_t> (point_step);
  cloud.row_step = static_cast<std::uint32_t> (point_step * header.width);
  cloud.is_bigendian = false;
}

[[noreturn]] void
failTruncated (const std::string &path, const std::string &detail)
{
  fail (path, "PCD data does not match its header: " + detail);
}

/** One ascii value into its slot; false if it is not a number of the field's type. */
template <typename T>
bool
parseValue (std::string_view token, std::uint8_t *slot)
{
  if (token.size () > 1 && token[0] == '+' && token[1] != '-')
    token.remove_prefix (1);
  T value{};
  const auto [end, ec] = std::from_chars (token.data (), token.data () + token.size (), value);
  if (end != token.data () + token.size ())
    return false;
  if constexpr (std::is_floating_point_v<T>)
    if (ec == std::errc::result_out_of_range)
    {
      // Too small for T is read as PCL reads it (a denormal or zero); too large is refused.
      long double wide = 0.0L;
      const auto [wide_end, wide_ec] = std::from_chars (token.data (), token.data () + token.size (), wide);
      if (wide_ec != std::errc () || wide_end != token.data () + token.size () || !(std::fabs (wide) < 1.0L))
        return false;
      value = static_cast<T> (wide);
      std::memcpy (slot, &value, sizeof (T));
      return true;
    }
  if (ec != std::errc ())
    return false;
  std::memcpy (slot, &value, sizeof (T));
  return true;
}

template <typename T>
bool
parseNarrowed (std::string_view token, std::uint8_t *slot)
{
  using Wide = std::conditional_t<std::is_signed_v<T>, std::int64_t, std::uint64_t>;
  std::uint8_t wide[sizeof (Wide)];
  if (!parseValue<Wide> (token, wide))
    return false;
  Wide value;
  std::memcpy (&value, wide, sizeof (Wide));
  if (value < Wide (std::numeric_limits<T>::min ()) || value > Wide (std::numeric_limits<T>::max ()))
    return false;
  const T narrow = static_cast<T> (value);
  std::memcpy (slot, &narrow, sizeof (T));
  return true;
}

bool
parseField (std::uint8_t datatype, std::string_view token, std::uint8_t *slot)
{
  switch (datatype)
  {
  case pcl::PCLPointField::FLOAT32: return parseValue<float> (token, slot);
  case pcl::PCLPointField::FLOAT64: return parseValue<double> (token, slot);
  case pcl::PCLPointField::INT8: return parseNarrowed<std::int8_t> (token, slot);
  case pcl::PCLPointField::INT16: return parseNarrowed<std::int16_t> (token, slot);
  case pcl::PCLPointField::INT32: return parseNarrowed<std::int32_t> (token, slot);
  case pcl::PCLPointField::INT64: return parseValue<std::int64_t> (token, slot);
  case pcl::PCLPointField::UINT8: return parseNarrowed<std::uint8_t> (token, slot);
  case pcl::PCLPointField::UINT16: return parseNarrowed<std::uint16_t> (token, slot);
  case pcl::PCLPointField::UINT32: return parseNarrowed<std::uint32_t> (token, slot);
  case pcl::PCLPointField::UINT64: return parseValue<std::uint64_t> (token, slot);
  case pcl::PCLPointField::BOOL: return parseNarrowed<std::uint8_t> (token, slot);
  default: return false;
  }
}

/** DATA ascii: one line per point (empty lines skipped, as PCL does), one number per value. */
void
readAscii (const std::string &path, std::string_view body, pcl::PCLPointCloud2 &cloud)
{
  std::size_t values_per_point = 0;
  for (const auto &f : cloud.fields)
    values_per_point += f.count;
  const std::size_t points = std::size_t (cloud.width) * cloud.height;
  std::size_t point = 0, pos = 0, line_number = 0;
  std::uint8_t *data = cloud.data.data ();
  while (pos < body.size ())
  {
    std::size_t end = body.find ('\n', pos);
    if (end == std::string_view::npos)
      end = body.size ();
    const std::string_view line = body.substr (pos, end - pos);
    pos = end + 1;
    ++line_number;
    const std::vector<std::string_view> tokens = splitWords (line);
    if (tokens.empty ())
      continue;
    if (point == points)
      fail (path, "PCD ascii data has more lines than its " + std::to_string (points) + " points (data line " +
                      std::to_string (line_number) + ")");
    if (tokens.size () != values_per_point)
      fail (path, "PCD ascii point " + std::to_string (point + 1) + " has " + std::to_string (tokens.size ()) +
                      " values, the header " + std::to_string (values_per_point) + " (data line " +
                      std::to_string (line_number) + ")");
    std::size_t t = 0;
    for (const auto &f : cloud.fields)
    {
      const std::size_t size = pcl::getFieldSize (f.datatype);
      for (std::uint32_t c = 0; c < f.count; ++c, ++t)
        if (!parseField (f.datatype, tokens[t], data + point * cloud.point_step + f.offset + c * size))
          fail (path, "PCD ascii point " + std::to_string (point + 1) + ": '" + shown (tokens[t]) +
                          "' is not a number of field '" + f.name + "' (TYPE and SIZE " + typeName (f.datatype) + ")");
    }
    ++point;
  }
  if (point != points)
    failTruncated (path, "ascii data has " + std::to_string (point) + " points, the header " + std::to_string (points));
}

/** LZF (liblzf's format, as PCL writes it), every copy checked against both buffers.
  * Returns the number of bytes written. */
std::size_t
lzfDecompress (const std::string &path, const std::uint8_t *in, std::size_t in_size, std::uint8_t *out,
               std::size_t out_size)
{
  const std::string corrupt = "compressed PCD data is corrupted: ";
  std::size_t ip = 0, op = 0;
  while (ip < in_size)
  {
    const unsigned ctrl = in[ip++];
    if (ctrl < (1u << 5))  // a run of ctrl + 1 literal bytes
    {
      const std::size_t run = ctrl + 1;
      if (run > in_size - ip)
        fail (path, corrupt + "a literal run of " + std::to_string (run) + " bytes at byte " + std::to_string (ip - 1) +
                        " goes past the end of the compressed data");
      if (run > out_size - op)
        fail (path, corrupt + "it decompresses to more than the " + std::to_string (out_size) + " bytes the header says");
      std::memcpy (out + op, in + ip, run);
      ip += run;
      op += run;
      continue;
    }
    // A back-reference: copy len + 2 bytes from distance back in the output.
    std::size_t len = ctrl >> 5;
    if (ip >= in_size)
      fail (path, corrupt + "a back-reference is cut off at its end");
    if (len == 7)
    {
      len += in[ip++];
      if (ip >= in_size)
        fail (path, corrupt + "a back-reference is cut off at its end");
    }
    const std::size_t distance = ((std::size_t (ctrl) & 0x1f) << 8) + in[ip++] + 1;
    len += 2;
    if (distance > op)
      fail (path, corrupt + "a back-reference at byte " + std::to_string (ip) + " points " + std::to_string (distance) +
                      " bytes back, before the start of the data (" + std::to_string (op) + " bytes written)");
    if (len > out_size - op)
      fail (path, corrupt + "it decompresses to more than the " + std::to_string (out_size) + " bytes the header says");
    // Byte by byte: source and destination overlap when distance < len (a repeating run).
    for (std::size_t k = 0; k < len; ++k, ++op)
      out[op] = out[op - distance];
  }
  return op;
}

/** DATA binary_compressed: sizes, LZF, then PCL's field-major layout (all x, all y, ...)
  * back to point-major. */
void
readCompressed (const std::string &path, std::ifstream &in, std::uint64_t available, std::uint64_t expected,
                pcl::PCLPointCloud2 &cloud)
{
  std::uint32_t sizes[2] = {0, 0};
  if (available < 8 || !in.read (reinterpret_cast<char *> (sizes), 8))
    failTruncated (path, "the compressed block has no sizes");
  const std::uint64_t compressed = sizes[0], uncompressed = sizes[1];
  if (uncompressed != expected)
    fail (path, "compressed PCD data claims " + std::to_string (uncompressed) + " bytes, the header " +
                    std::to_string (expected) + " (corrupted)");
  if (compressed > available - 8)
    failTruncated (path, "the compressed block claims " + std::to_string (compressed) + " bytes, the file holds " +
                             std::to_string (available - 8));
  if (expected == 0)
    return;
  // An LZF byte yields at most 88 (a 3-byte back-reference copies 264): refused before allocating.
  if (expected > compressed * 88)
    fail (path, "compressed PCD data of " + std::to_string (compressed) + " bytes cannot hold the " +
                    std::to_string (expected) + " the header says (corrupted)");
  // All literals is LZF's worst case: a run byte per 32 bytes.
  if (compressed > expected + expected / 32 + 16)
    fail (path, "compressed PCD data of " + std::to_string (compressed) + " bytes is more than LZF makes of the " +
                    std::to_string (expected) + " the header says (corrupted)");
  cloud.data.resize (expected);
  std::vector<std::uint8_t> packed (compressed);
  if (!in.read (reinterpret_cast<char *> (packed.data ()), static_cast<std::streamsize> (compressed)))
    failTruncated (path, "the compressed block could not be read");
  std::vector<std::uint8_t> field_major (expected);
  const std::size_t written = lzfDecompress (path, packed.data (), packed.size (), field_major.data (), expected);
  if (written != expected)
    fail (path, "compressed PCD data decompresses to " + std::to_string (written) + " bytes, the header says " +
                    std::to_string (expected) + " (corrupted)");
  const std::size_t points = std::size_t (cloud.width) * cloud.height;
  const std::uint8_t *src = field_major.data ();
  for (const auto &f : cloud.fields)
  {
    const std::size_t bytes = pcl::getFieldSize (f.datatype) * f.count;
    std::uint8_t *dst = cloud.data.data () + f.offset;
    if (bytes == 4)  // the common case (float x, y, z, rgba), kept cheap
      for (std::size_t i = 0; i < points; ++i, src += 4, dst += cloud.point_step)
        std::memcpy (dst, src, 4);
    else
      for (std::size_t i = 0; i < points; ++i, src += bytes, dst += cloud.point_step)
        std::memcpy (dst, src, bytes);
  }
}

/** Dense when none of the x, y, z values is NaN or infinite (PCL's readers differ in
  * detail: its binary reader looks at every float field, its ascii reader only at "nan"
  * tokens; agex uses only x, y, z and treats every invalid point the same way). */
bool
isDense (const pcl::PCLPointCloud2 &cloud)
{
  const std::size_t points = std::size_t (cloud.width) * cloud.height;
  for (const auto &f : cloud.fields)
  {
    if (f.name != "x" && f.name != "y" && f.name != "z")
      continue;
    for (std::size_t i = 0; i < points; ++i)
      for (std::uint32_t c = 0; c < f.count; ++c)
      {
        const std::uint8_t *slot = cloud.data.data () + i * cloud.point_step + f.offset;
        if (f.datatype == pcl::PCLPointField::FLOAT32)
        {
          float v;
          std::memcpy (&v, slot + 4 * c, 4);
          if (!std::isfinite (v))
            return false;
        }
        else if (f.datatype == pcl::PCLPointField::FLOAT64)
        {
          double v;
          std::memcpy (&v, slot + 8 * c, 8);
          if (!std::isfinite (v))
            return false;
        }
      }
  }
  return true;
}
}  // namespace

pcl::PCLPointCloud2
readPcd (const std::string &path)
{
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    fail (path, problem + "; frames are read from regular files only");
  std::ifstream in (path, std::ios::binary | std::ios::ate);
  if (!in)
    fail (path, "cannot open file");
  const std::streamoff file_end = in.tellg ();
  if (file_end < 0)
    fail (path, "cannot read file");
  const std::uint64_t file_size = static_cast<std::uint64_t> (file_end);
  std::string head (static_cast<std::size_t> (std::min<std::uint64_t> (file_size, kMaxHeaderBytes)), '\0');
  in.seekg (0);
  if (!in.read (head.data (), static_cast<std::streamsize> (head.size ())))
    fail (path, "cannot read file");
  const PcdHeader header = parseHeader (path, head, head.size () == file_size);

  pcl::PCLPointCloud2 cloud;
  layOutCloud (path, header, cloud);
  const std::uint64_t bytes = header.points * cloud.point_step;
  const std::uint64_t available = file_size - header.data_offset;
  in.clear ();
  in.seekg (static_cast<std::streamoff> (header.data_offset));
  if (header.data == "binary")
  {
    if (available < bytes)
      failTruncated (path, "binary data of " + std::to_string (available) + " bytes, the header " + std::to_string (bytes));
    cloud.data.resize (bytes);
    if (!in.read (reinterpret_cast<char *> (cloud.data.data ()), static_cast<std::streamsize> (bytes)))
      failTruncated (path, "binary data could not be read");
  }
  else if (header.data == "binary_compressed")
  {
    readCompressed (path, in, available, bytes, cloud);
  }
  else
  {
    // A value takes at least a character and a separator; a number over 64 characters long
    // is no number PCL writes. Both bounds come before anything of the claimed size is read.
    std::uint64_t values = 0;
    for (const auto &f : cloud.fields)
      values += f.count;
    if (header.points > 0 && available < header.points * values * 2 - 1)
      failTruncated (path, "ascii data of " + std::to_string (available) + " bytes cannot hold " +
                               std::to_string (header.points) + " points");
    if (available > header.points * values * 65 + kMaxHeaderBytes)
      fail (path, "PCD ascii data of " + std::to_string (available) + " bytes is far more than " +
                      std::to_string (header.points) + " points take (damaged POINTS line)");
    // The text is read whole: keep it within the data limit too.
    if (available > kMaxPcdDataBytes)
      fail (path, "PCD ascii data of " + std::to_string (available) + " bytes is more than the " +
                      std::to_string (kMaxPcdDataBytes) + " agex reads");
    std::string body (static_cast<std::size_t> (available), '\0');
    if (!in.read (body.data (), static_cast<std::streamsize> (available)))
      failTruncated (path, "ascii data could not be read");
    cloud.data.resize (bytes);
    readAscii (path, body, cloud);
  }
  cloud.is_dense = isDense (cloud);
  return cloud;
}
}  // namespace agex

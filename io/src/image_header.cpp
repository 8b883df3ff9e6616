#include <agex/io/image_header.h>

#include <agex/io/frame_io.h>
#include <agex/io/input_file.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace agex
{
namespace
{
/** Bounded reads of the bytes at hand: anything past the end reads as 0 and marks short. */
struct Bytes
{
  const unsigned char *data;
  std::size_t size;
  mutable bool short_read = false;

  unsigned
  u8 (std::size_t at) const
  {
    if (at >= size)
    {
      short_read = true;
      return 0;
    }
    return data[at];
  }
  std::uint32_t u16 (std::size_t at, bool big) const
  {
    return big ? u8 (at) << 8 | u8 (at + 1) : u8 (at + 1) << 8 | u8 (at);
  }
  std::uint32_t u32 (std::size_t at, bool big) const
  {
    return big ? u16 (at, true) << 16 | u16 (at + 2, true) : u16 (at + 2, false) << 16 | u16 (at, false);
  }
  bool starts (std::size_t at, const char *magic, std::size_t n) const
  {
    return at + n <= size && std::memcmp (data + at, magic, n) == 0;
  }
};

std::string
sizeText (std::uint64_t w, std::uint64_t h)
{
  return std::to_string (w) + "x" + std::to_string (h);
}

// JPEG (ITU T.81 B.1): segments walked, entropy-coded data skipped to its next marker. libjpeg
// takes the first frame header (SOF) and refuses another; others may not, so any frame header
// that disagrees is refused, whether before or after the first scan. Markers are found as
// libjpeg's next_marker () finds them: bytes before an 0xFF are skipped, and FF 00 outside a
// scan is no marker (a segment length read there would hide the frame header behind it).
std::string
jpegHeader (const Bytes &b, ImageHeader &header)
{
  std::size_t i = 2;
  bool have_sof = false;
  while (i < b.size)
  {
    while (i < b.size && b.u8 (i) != 0xFF)
      ++i;  // extraneous bytes: libjpeg warns and skips them
    while (i < b.size && b.u8 (i) == 0xFF)
      ++i;  // fill bytes
    if (i >= b.size)
      break;
    const unsigned marker = b.u8 (i++);
    if (marker == 0x00)
      continue;  // a stuffed zero: no marker, the search goes on
    if (marker == 0xD9)
      return have_sof ? "" : "damaged JPEG: no frame header (SOF) before its end";
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8))
      continue;  // markers without a segment
    if (i + 2 > b.size)
      break;
    const std::size_t length = b.u16 (i, true);
    if (length < 2)
      return "damaged JPEG: a segment of length " + std::to_string (length) + " at byte " + std::to_string (i);
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof)
    {
      if (i + 7 > b.size)
        break;
      const std::uint64_t h = b.u16 (i + 3, true), w = b.u16 (i + 5, true);
      if (have_sof && (w != header.width || h != header.height))
        return "a JPEG with two frame headers (SOF) that disagree: " + sizeText (header.width, header.height) +
               ", then " + sizeText (w, h) + " at byte " + std::to_string (i - 2);
      header.width = w;
      header.height = h;
      have_sof = true;
    }
    i += length;
    if (marker == 0xDA)
    {
      // Entropy-coded data runs to the next marker: 0xFF not followed by a stuffed zero or a
      // restart marker.
      while (i + 1 < b.size &&
             !(b.u8 (i) == 0xFF && b.u8 (i + 1) != 0 && (b.u8 (i + 1) < 0xD0 || b.u8 (i + 1) > 0xD7)))
        ++i;
      if (i + 1 >= b.size)
        break;
    }
  }
  return "truncated JPEG (the data ends before its end-of-image marker)";
}

// Classic TIFF: ImageWidth (256) and ImageLength (257) of the first directory, the one
// OpenCV's decoder reads.
std::string
tiffHeader (const Bytes &b, ImageHeader &header)
{
  const bool big = b.u8 (0) == 'M';
  const std::uint64_t ifd = b.u32 (4, big);
  const std::uint32_t entries = b.u16 (ifd, big);
  if (b.short_read || ifd < 8 || ifd + 2 + std::uint64_t (entries) * 12 > b.size)
    return "damaged TIFF: its first directory is not in the file";
  bool have_width = false, have_height = false;
  for (std::uint32_t e = 0; e < entries; ++e)
  {
    const std::size_t at = static_cast<std::size_t> (ifd) + 2 + e * 12;
    const std::uint32_t tag = b.u16 (at, big), type = b.u16 (at + 2, big), count = b.u32 (at + 4, big);
    if ((tag != 256 && tag != 257) || count != 1)
      continue;
    // libtiff takes the first of two equal tags; a reader that took the last would be fooled.
    if (tag == 256 ? have_width : have_height)
      return "damaged TIFF: its first directory gives the image " + std::string (tag == 256 ? "width" : "length") +
             " twice";
    // BYTE (1), SHORT (3) or LONG (4); a BYTE or SHORT is left-aligned in the value field.
    std::uint64_t value;
    if (type == 1)
      value = b.u8 (at + 8);
    else if (type == 3)
      value = b.u16 (at + 8, big);
    else if (type == 4)
      value = b.u32 (at + 8, big);
    else
      return "damaged TIFF: image " + std::string (tag == 256 ? "width" : "length") + " of type " +
             std::to_string (type);
    (tag == 256 ? header.width : header.height) = value;
    (tag == 256 ? have_width : have_height) = true;
  }
  if (!have_width || !have_height)
    return "damaged TIFF: no image width and length in its first directory";
  return "";
}

// WebP (RIFF): the VP8X canvas if there is one (libwebp's WebPGetFeatures), else the VP8 or
// VP8L bitstream's size.
std::string
webpHeader (const Bytes &b, ImageHeader &header)
{
  if (b.starts (12, "VP8X", 4))
  {
    header.width = 1 + (b.u8 (24) | b.u8 (25) << 8 | std::uint64_t (b.u8 (26)) << 16);
    header.height = 1 + (b.u8 (27) | b.u8 (28) << 8 | std::uint64_t (b.u8 (29)) << 16);
  }
  else if (b.starts (12, "VP8 ", 4))
  {
    if (!(b.u8 (23) == 0x9D && b.u8 (24) == 0x01 && b.u8 (25) == 0x2A))
      return "damaged WebP: no VP8 start code";
    header.width = b.u16 (26, false) & 0x3FFF;
    header.height = b.u16 (28, false) & 0x3FFF;
  }
  else if (b.starts (12, "VP8L", 4))
  {
    if (b.u8 (20) != 0x2F)
      return "damaged WebP: no VP8L signature";
    const std::uint32_t bits = b.u32 (21, false);
    header.width = 1 + (bits & 0x3FFF);
    header.height = 1 + ((bits >> 14) & 0x3FFF);
  }
  else
    return "damaged WebP: no VP8X, VP8 or VP8L chunk first";
  return b.short_read ? "truncated WebP header" : "";
}

// BMP: a BITMAPCOREHEADER (12 bytes, unsigned 16-bit size) or a later one (signed 32-bit,
// a negative height for top-down rows).
std::string
bmpHeader (const Bytes &b, ImageHeader &header)
{
  const std::uint32_t info = b.u32 (14, false);
  if (info == 12)
  {
    header.width = b.u16 (18, false);
    header.height = b.u16 (20, false);
  }
  else
  {
    const std::int64_t w = static_cast<std::int32_t> (b.u32 (18, false));
    const std::int64_t h = static_cast<std::int32_t> (b.u32 (22, false));
    header.width = static_cast<std::uint64_t> (w < 0 ? -w : w);
    header.height = static_cast<std::uint64_t> (h < 0 ? -h : h);
  }
  return b.short_read ? "truncated BMP header" : "";
}

/** The next decimal of a PNM header (whitespace and '#' comments between), saturated at 2^32. */
bool
pnmNumber (const Bytes &b, std::size_t &i, std::uint64_t &value)
{
  for (;;)
  {
    while (i < b.size && std::strchr (" \t\r\n\v\f", static_cast<int> (b.u8 (i))) && b.u8 (i) != 0)
      ++i;
    if (i < b.size && b.u8 (i) == '#')
      while (i < b.size && b.u8 (i) != '\n' && b.u8 (i) != '\r')
        ++i;
    else
      break;
  }
  if (i >= b.size || b.u8 (i) < '0' || b.u8 (i) > '9')
    return false;
  value = 0;
  for (; i < b.size && b.u8 (i) >= '0' && b.u8 (i) <= '9'; ++i)
    value = std::min<std::uint64_t> (value * 10 + (b.u8 (i) - '0'), std::uint64_t (1) << 32);
  // OpenCV's ReadNumber consumes the byte that ends a number, whatever it is: "30000#300000"
  // is 30000 then 300000 to it, not 30000 and a comment.
  if (i < b.size)
    ++i;
  return true;
}

// PAM: "WIDTH n" and "HEIGHT n" lines before ENDHDR.
std::string
pamHeader (const Bytes &b, ImageHeader &header)
{
  std::size_t i = 3;
  bool have_width = false, have_height = false;
  while (i < b.size && i < 4096)
  {
    std::size_t end = i;
    while (end < b.size && b.u8 (end) != '\n')
      ++end;
    std::string line (reinterpret_cast<const char *> (b.data) + i, end - i);
    i = end + 1;
    // OpenCV's PAM reader also ends a line at a carriage return and skips leading white space:
    // a header read line by line differently could hide a second size. Refused, not guessed.
    if (line.find ('\r') != std::string::npos)
      return "damaged PAM header: a carriage return in its header";
    line.erase (0, line.find_first_not_of (" \t\v\f"));
    std::size_t at = 0;
    if (line.rfind ("ENDHDR", 0) == 0)
      return have_width && have_height ? "" : "damaged PAM header: no WIDTH or HEIGHT";
    for (const char *key : {"WIDTH", "HEIGHT"})
      if (line.rfind (key, 0) == 0)
      {
        at = std::strlen (key);
        std::uint64_t value = 0;
        const Bytes field{reinterpret_cast<const unsigned char *> (line.data ()), line.size ()};
        if (!pnmNumber (field, at, value))
          return std::string ("damaged PAM header: ") + key + " is not a number";
        if (key[0] == 'W' ? have_width : have_height)
          return std::string ("damaged PAM header: ") + key + " given twice";
        (key[0] == 'W' ? header.width : header.height) = value;
        (key[0] == 'W' ? have_width : have_height) = true;
      }
  }
  return "damaged PAM header: no ENDHDR in its first 4096 bytes";
}
}  // namespace

std::string
parseImageHeader (const unsigned char *data, std::size_t size, ImageHeader &header)
{
  header = ImageHeader ();
  const Bytes b{data, size};
  const auto named = [&] (const char *format) {
    header.format = format;
    return true;
  };
  if (pngHeaderSize (data, size, header.width, header.height) && named ("PNG"))
    return "";
  if (b.starts (0, "\xFF\xD8\xFF", 3) && named ("JPEG"))
    return jpegHeader (b, header);
  if ((b.starts (0, "II*\0", 4) || b.starts (0, "MM\0*", 4)) && named ("TIFF"))
    return tiffHeader (b, header);
  if (b.starts (0, "RIFF", 4) && b.starts (8, "WEBP", 4) && named ("WebP"))
    return webpHeader (b, header);
  if (b.starts (0, "BM", 2) && named ("BMP"))
    return bmpHeader (b, header);
  if (b.starts (0, "\x59\xA6\x6A\x95", 4) && named ("Sun raster"))
  {
    header.width = b.u32 (4, true);
    header.height = b.u32 (8, true);
    return b.short_read ? "truncated Sun raster header" : "";
  }
  if (size >= 3 && b.u8 (0) == 'P' && b.u8 (1) == '7' && std::isspace (b.u8 (2)) && named ("PAM"))
    return pamHeader (b, header);
  if (size >= 3 && b.u8 (0) == 'P' && std::strchr ("123456Ff", static_cast<int> (b.u8 (1))) && b.u8 (1) != 0 &&
      std::isspace (b.u8 (2)))
  {
    named (b.u8 (1) == 'F' || b.u8 (1) == 'f' ? "PFM" : "PNM");
    std::size_t i = 2;
    if (!pnmNumber (b, i, header.width) || !pnmNumber (b, i, header.height))
      return "damaged " + header.format + " header: no width and height";
    return "";
  }
  // Formats OpenCV may decode that agex does not check.
  if (b.starts (0, "II+\0", 4) || b.starts (0, "MM\0+", 4))
    return "a BigTIFF image, which agex does not read (convert it to PNG)";
  if (b.starts (0, "#?RADIANCE", 10) || b.starts (0, "#?RGBE", 6))
    return "a Radiance HDR image, which agex does not read (convert it to PNG)";
  if (b.starts (0, "\x00\x00\x00\x0CjP  ", 8) || b.starts (0, "\xFF\x4F\xFF\x51", 4))
    return "a JPEG 2000 image, which agex does not read (convert it to PNG)";
  if (b.starts (0, "\x76\x2F\x31\x01", 4))
    return "an OpenEXR image, which agex does not read (convert it to PNG)";
  if (size == 0)
    return "empty file, not an image";
  return "not an image agex reads (PNG, JPEG, TIFF, WebP, BMP, PNM, PAM, PFM, Sun raster)";
}

std::vector<unsigned char>
readImageBytes (const std::string &path, ImageHeader &header)
{
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw FrameError (path + ": " + problem + "; images are read from regular files only");
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size (path, ec);
  if (ec)
    throw FrameError (path + ": cannot read the image (" + ec.message () + ")");
  if (size > kMaxImageFileBytes)
    throw FrameError (path + ": " + std::to_string (size) + " bytes, larger than the " +
                      std::to_string (kMaxImageFileBytes) + " bytes of any image agex reads");
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw FrameError (path + ": cannot open the image");
  std::vector<unsigned char> bytes (static_cast<std::size_t> (size));
  in.read (reinterpret_cast<char *> (bytes.data ()), static_cast<std::streamsize> (size));
  bytes.resize (static_cast<std::size_t> (in.gcount ()));  // it may have shrunk since
  const std::string bad = parseImageHeader (bytes.data (), bytes.size (), header);
  if (!bad.empty ())
    throw FrameError (path + ": " + bad);
  checkFrameSize (path, header.width, header.height);
  return bytes;
}

cv::Mat
decodeImageBytes (const std::string &path, const std::vector<unsigned char> &bytes, int flags)
{
  try
  {
    return cv::imdecode (bytes, flags);
  }
  catch (const cv::Exception &e)
  {
    throw FrameError (path + ": OpenCV refused to decode it (" + e.err + ")");
  }
}

cv::Mat
readImageFile (const std::string &path, int flags, std::vector<unsigned char> *bytes_out)
{
  ImageHeader header;
  std::vector<unsigned char> bytes = readImageBytes (path, header);
  const cv::Mat image = decodeImageBytes (path, bytes, flags);
  if (image.empty ())
    throw FrameError (path + ": not an image OpenCV can decode (a damaged " + header.format + ")");
  checkFrameSize (path, static_cast<std::uint64_t> (image.cols), static_cast<std::uint64_t> (image.rows));
  if (bytes_out)
    *bytes_out = std::move (bytes);
  return image;
}
}  // namespace agex

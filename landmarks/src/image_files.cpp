#include <agex/landmarks/image_files.h>

#include <agex/io/frame_io.h>
#include <agex/io/input_file.h>

#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <vector>

namespace agex
{
namespace
{
struct ImageHeader
{
  std::uint64_t width = 0, height = 0;  ///< 0: not found in the header
  bool truncated = false;
};

// Size from a PNG's IHDR or a JPEG's SOF segment, and whether a JPEG reaches its
// end-of-image marker. Segments are walked and entropy-coded data skipped, so data a camera
// appends after the marker does no harm. Anything it cannot parse is left to the decoder.
ImageHeader
probeImage (const std::string &b)
{
  ImageHeader header;
  const auto byte = [&] (std::size_t i) { return static_cast<unsigned char> (b[i]); };
  const std::size_t n = b.size ();
  if (pngHeaderSize (reinterpret_cast<const unsigned char *> (b.data ()), n, header.width, header.height))
    return header;
  if (n < 2 || byte (0) != 0xFF || byte (1) != 0xD8)
    return header;
  std::size_t i = 2;
  while (i < n)
  {
    if (byte (i) != 0xFF)
      return header;  // not a marker where one belongs: let the decoder judge
    while (i < n && byte (i) == 0xFF)
      ++i;  // fill bytes
    if (i >= n)
      break;
    const unsigned char marker = byte (i++);
    if (marker == 0xD9)
      return header;  // end of image
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8))
      continue;  // markers without a segment
    if (i + 2 > n)
      break;
    const std::size_t length = static_cast<std::size_t> (byte (i)) << 8 | byte (i + 1);
    if (length < 2)
      return header;
    const bool frame_header = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header && i + 7 <= n)
    {
      header.height = static_cast<std::uint64_t> (byte (i + 3)) << 8 | byte (i + 4);
      header.width = static_cast<std::uint64_t> (byte (i + 5)) << 8 | byte (i + 6);
    }
    i += length;
    if (marker == 0xDA)
    {
      // Entropy-coded data runs to the next marker: 0xFF not followed by a stuffed zero
      // or a restart marker.
      while (i + 1 < n && !(byte (i) == 0xFF && byte (i + 1) != 0 && (byte (i + 1) < 0xD0 || byte (i + 1) > 0xD7)))
        ++i;
      if (i + 1 >= n)
        break;
    }
  }
  header.truncated = true;
  return header;
}

std::uint32_t
bigEndian32 (const std::string &b, std::size_t at)
{
  return static_cast<std::uint32_t> (static_cast<unsigned char> (b[at])) << 24 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 1])) << 16 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 2])) << 8 |
         static_cast<std::uint32_t> (static_cast<unsigned char> (b[at + 3]));
}

// The palette of a palette PNG (colour type 3), as BGR; empty for any other file.
std::vector<cv::Vec3b>
pngPalette (const std::string &bytes)
{
  static const char signature[] = "\x89PNG\r\n\x1a\n";
  if (bytes.size () < 33 || bytes.compare (0, 8, signature, 8) != 0 || bytes.compare (12, 4, "IHDR") != 0 ||
      bytes[25] != 3)
    return {};
  std::size_t at = 8;
  while (at + 12 <= bytes.size ())
  {
    const std::uint32_t length = bigEndian32 (bytes, at);
    if (length > bytes.size () - at - 12)
      break;
    if (bytes.compare (at + 4, 4, "PLTE") == 0)
    {
      std::vector<cv::Vec3b> palette;
      for (std::size_t i = 0; i + 2 < length; i += 3)
        palette.emplace_back (bytes[at + 8 + i + 2], bytes[at + 8 + i + 1], bytes[at + 8 + i]);
      return palette;
    }
    at += 12 + length;
  }
  return {};
}
}  // namespace

cv::Mat
readImage (const std::string &path, int flags, const std::string &role)
{
  const std::string what = role.empty () ? "" : " (" + role + ")";
  // Before opening: a FIFO would block until some other process writes to it.
  const std::string problem = notARegularFile (path);
  if (!problem.empty ())
    throw std::runtime_error (path + ": " + problem + "; images are read from regular files only" + what);
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw std::runtime_error (path + ": cannot open the image" + what);
  const std::string bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  if (bytes.empty ())
    throw std::runtime_error (path + ": empty file, not an image" + what);
  const ImageHeader header = probeImage (bytes);
  const auto too_large = [&] (std::uint64_t width, std::uint64_t height) {
    if (width * height > kMaxFramePixels)
      throw std::runtime_error (path + ": a " + std::to_string (width) + "x" + std::to_string (height) +
                                " image, more than the " + std::to_string (kMaxFramePixels) + " pixels agex reads" + what);
  };
  too_large (header.width, header.height);
  if (header.truncated)
    throw std::runtime_error (path + ": truncated JPEG (the data ends before its end-of-image marker)" + what);
  const cv::Mat image = cv::imdecode (cv::Mat (1, static_cast<int> (bytes.size ()), CV_8UC1,
                                               const_cast<char *> (bytes.data ())), flags);
  if (image.empty ())
    throw std::runtime_error (path + ": not an image OpenCV can decode" + what);
  too_large (static_cast<std::uint64_t> (image.cols), static_cast<std::uint64_t> (image.rows));
  return image;
}

cv::Mat
readLabelImage (const std::string &path)
{
  const cv::Mat decoded = readImage (path, cv::IMREAD_UNCHANGED, "a mask");
  if (decoded.type () == CV_8UC1 || decoded.type () == CV_16UC1)
    return decoded;
  std::ifstream in (path, std::ios::binary);
  const std::string bytes ((std::istreambuf_iterator<char> (in)), std::istreambuf_iterator<char> ());
  const std::vector<cv::Vec3b> palette = pngPalette (bytes);
  if (palette.empty () || decoded.type () != CV_8UC3)
    throw std::runtime_error (path + ": a " + std::to_string (decoded.channels ()) +
                              "-channel image, not a mask (label or instance masks are 8 or 16-bit grey, or palette PNGs)");
  // Back from colours to indices; a colour listed twice means its first index (unused
  // palette entries are usually black, like the background at index 0).
  std::map<std::uint32_t, unsigned char> index;
  for (std::size_t i = palette.size (); i-- > 0;)
    index[palette[i][0] << 16 | palette[i][1] << 8 | palette[i][2]] = static_cast<unsigned char> (i);
  cv::Mat labels (decoded.size (), CV_8UC1);
  for (int y = 0; y < decoded.rows; ++y)
    for (int x = 0; x < decoded.cols; ++x)
    {
      const cv::Vec3b c = decoded.at<cv::Vec3b> (y, x);
      const auto it = index.find (c[0] << 16 | c[1] << 8 | c[2]);
      if (it == index.end ())
        throw std::runtime_error (path + ": pixel (" + std::to_string (x) + ", " + std::to_string (y) +
                                  ") has a colour that is not in the PNG's palette");
      labels.at<unsigned char> (y, x) = it->second;
    }
  return labels;
}
}  // namespace agex

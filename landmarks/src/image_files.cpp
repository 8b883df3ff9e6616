#include <agex/landmarks/image_files.h>

#include <agex/io/frame_io.h>
#include <agex/io/image_header.h>
#include <agex/io/input_file.h>

#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <map>
#include <stdexcept>
#include <vector>

namespace agex
{
namespace
{
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

namespace
{
/** io's checked read, its message naming what the image was needed for. */
cv::Mat
decodeImage (const std::string &path, int flags, const std::string &role, std::vector<unsigned char> &bytes)
{
  const std::string what = role.empty () ? "" : " (" + role + ")";
  try
  {
    return readImageFile (path, flags, &bytes);
  }
  catch (const FrameError &e)
  {
    throw std::runtime_error (e.what () + what);
  }
}
}  // namespace

cv::Mat
readImage (const std::string &path, int flags, const std::string &role)
{
  std::vector<unsigned char> bytes;
  return decodeImage (path, flags, role, bytes);
}

cv::Mat
readLabelImage (const std::string &path)
{
  std::vector<unsigned char> bytes;
  const cv::Mat decoded = decodeImage (path, cv::IMREAD_UNCHANGED, "a mask", bytes);
  if (decoded.type () == CV_8UC1 || decoded.type () == CV_16UC1)
    return decoded;
  const std::vector<cv::Vec3b> palette = pngPalette (std::string (bytes.begin (), bytes.end ()));
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

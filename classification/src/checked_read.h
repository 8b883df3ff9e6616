#pragma once
// Reading model files: every field is checked for presence and type, so a damaged
// file gives a ModelError instead of OpenCV's silent defaults. Private to this module.

#include <agex/classification/model_error.h>

#include <opencv2/core.hpp>

#include <string>

namespace agex
{
namespace detail
{
inline int
readInt (const cv::FileNode &node, const char *name)
{
  const cv::FileNode n = node[name];
  if (n.empty () || !n.isInt ())
    throw ModelError (std::string ("missing or invalid integer '") + name + "'");
  return static_cast<int> (n);
}

inline double
readReal (const cv::FileNode &node, const char *name)
{
  const cv::FileNode n = node[name];
  if (n.empty () || !(n.isReal () || n.isInt ()))
    throw ModelError (std::string ("missing or invalid number '") + name + "'");
  return static_cast<double> (n);
}

inline std::string
readString (const cv::FileNode &node, const char *name)
{
  const cv::FileNode n = node[name];
  if (n.empty () || !n.isString ())
    throw ModelError (std::string ("missing or invalid string '") + name + "'");
  return static_cast<std::string> (n);
}
}  // namespace detail
}  // namespace agex

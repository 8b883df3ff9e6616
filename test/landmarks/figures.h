#pragma once
// What the landmark tests draw and where they write: a stick figure whose extremities are
// known (test/landmarks and the apps' runs in test/apps share it), and a fresh temporary
// folder per test.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include <unistd.h>

namespace landmark_test
{
namespace fs = std::filesystem;

inline fs::path
tempDir (const std::string &name)
{
  const fs::path dir = fs::temp_directory_path () / ("agex_test_landmarks_" + name + "_" + std::to_string (::getpid ()));
  fs::remove_all (dir);
  fs::create_directories (dir);
  return dir;
}

// A figure with a round head, a trunk, arms out at arm_angle (radians below horizontal)
// and legs apart: its extremities are known.
struct Figure
{
  cv::Mat mask;
  cv::Point2f head_top, hand_left, hand_right, foot_left, foot_right;
};

inline Figure
drawFigure (cv::Size size, cv::Point2f centre, float scale, float arm_angle, float leg_spread)
{
  Figure f;
  f.mask = cv::Mat::zeros (size, CV_8UC1);
  const float head_r = 12 * scale;
  const cv::Point2f neck = centre + cv::Point2f (0, -40 * scale), hip = centre + cv::Point2f (0, 30 * scale);
  const cv::Point2f head = neck + cv::Point2f (0, -head_r);
  const float arm = 55 * scale, leg = 70 * scale, thick = 7 * scale;
  f.head_top = head + cv::Point2f (0, -head_r);
  const cv::Point2f shoulder = neck + cv::Point2f (0, 8 * scale);
  f.hand_left = shoulder + cv::Point2f (-std::cos (arm_angle), std::sin (arm_angle)) * arm;
  f.hand_right = shoulder + cv::Point2f (std::cos (arm_angle), std::sin (arm_angle)) * arm;
  f.foot_left = hip + cv::Point2f (-std::sin (leg_spread), std::cos (leg_spread)) * leg;
  f.foot_right = hip + cv::Point2f (std::sin (leg_spread), std::cos (leg_spread)) * leg;
  cv::circle (f.mask, head, static_cast<int> (head_r), 255, cv::FILLED);
  cv::line (f.mask, neck, hip, 255, static_cast<int> (4 * thick));
  for (const cv::Point2f &end : {f.hand_left, f.hand_right})
    cv::line (f.mask, shoulder, end, 255, static_cast<int> (thick));
  for (const cv::Point2f &end : {f.foot_left, f.foot_right})
    cv::line (f.mask, hip, end, 255, static_cast<int> (1.5f * thick));
  // The drawn ends stick out by half the line width.
  auto tip = [&] (const cv::Point2f &from, const cv::Point2f &to, float half) {
    const cv::Point2f d = to - from;
    return to + d * (half / static_cast<float> (cv::norm (d)));
  };
  f.hand_left = tip (shoulder, f.hand_left, thick / 2);
  f.hand_right = tip (shoulder, f.hand_right, thick / 2);
  f.foot_left = tip (hip, f.foot_left, 0.75f * thick);
  f.foot_right = tip (hip, f.foot_right, 0.75f * thick);
  return f;
}
}  // namespace landmark_test

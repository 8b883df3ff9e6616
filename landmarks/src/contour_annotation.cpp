#include <agex/landmarks/contour_annotation.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace agex
{
namespace
{
bool known (const cv::Point2f &p) { return std::isfinite (p.x) && std::isfinite (p.y); }
float dot (const cv::Point2f &a, const cv::Point2f &b) { return a.x * b.x + a.y * b.y; }

cv::Point2f
normalised (const cv::Point2f &v, const cv::Point2f &fallback)
{
  const float n = std::hypot (v.x, v.y);
  return n > 1e-6f && std::isfinite (n) ? v * (1.f / n) : fallback;
}

int
nearestContourIndex (const std::vector<cv::Point> &contour, const cv::Point2f &p, float *distance = nullptr)
{
  int best = 0;
  float best_d2 = std::numeric_limits<float>::max ();
  for (int i = 0; i < static_cast<int> (contour.size ()); ++i)
  {
    const cv::Point2f d = cv::Point2f (contour[i]) - p;
    const float d2 = dot (d, d);
    if (d2 < best_d2)
    {
      best_d2 = d2;
      best = i;
    }
  }
  if (distance)
    *distance = std::sqrt (best_d2);
  return best;
}

// Index of the largest score among contour points passing keep; -1 when none does. Ties
// (within half a pixel) resolve to the middle of the run, so a flat top gives its centre.
template <typename Score, typename Keep>
int
argmaxOnContour (const std::vector<cv::Point> &contour, Score score, Keep keep)
{
  float best = -std::numeric_limits<float>::max ();
  for (int i = 0; i < static_cast<int> (contour.size ()); ++i)
    if (keep (i))
      best = std::max (best, score (cv::Point2f (contour[i])));
  std::vector<int> near_best;
  for (int i = 0; i < static_cast<int> (contour.size ()); ++i)
    if (keep (i) && score (cv::Point2f (contour[i])) >= best - 0.5f)
      near_best.push_back (i);
  return near_best.empty () ? -1 : near_best[near_best.size () / 2];
}

// The outline of the largest piece of the mask, counter-clockwise on screen.
std::vector<cv::Point>
largestOuterContour (const cv::Mat &mask, const ContourAnnotationParams &params, std::string &problem)
{
  cv::Mat binary = mask > 0;
  const cv::Rect extent = cv::boundingRect (binary);
  if (extent.area () == 0)
  {
    problem = "empty mask";
    return {};
  }
  const int closing = params.closing_px >= 0 ? params.closing_px
                                             : std::max (1, static_cast<int> (std::lround (0.02 * extent.height)));
  if (closing > 0)
  {
    // Pad so that closing does not glue the person to the image border.
    cv::Mat padded;
    cv::copyMakeBorder (binary, padded, closing, closing, closing, closing, cv::BORDER_CONSTANT, 0);
    cv::morphologyEx (padded, padded, cv::MORPH_CLOSE,
                      cv::getStructuringElement (cv::MORPH_ELLIPSE, cv::Size (2 * closing + 1, 2 * closing + 1)));
    binary = padded (cv::Rect (closing, closing, mask.cols, mask.rows)).clone ();
  }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours (binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::size_t largest = 0;
  double largest_area = -1.0;
  for (std::size_t i = 0; i < contours.size (); ++i)
  {
    const double area = cv::contourArea (contours[i]);
    if (area > largest_area)
    {
      largest_area = area;
      largest = i;
    }
  }
  if (contours.empty () || largest_area < params.min_area_px)
  {
    problem = "mask smaller than " + std::to_string (params.min_area_px) + " pixels";
    return {};
  }
  std::vector<cv::Point> contour = std::move (contours[largest]);
  // With y pointing down, a screen counter-clockwise walk has a negative shoelace sum.
  if (cv::contourArea (contour, true) > 0)
    std::reverse (contour.begin (), contour.end ());
  return contour;
}

// Point at arc length s along the closed polyline (cumulative lengths in arc).
cv::Point2f
pointAtArcLength (const std::vector<cv::Point> &contour, const std::vector<double> &arc, double s)
{
  const double total = arc.back ();
  s = std::fmod (std::fmod (s, total) + total, total);
  const auto it = std::upper_bound (arc.begin (), arc.end (), s);
  const int segment = static_cast<int> (std::distance (arc.begin (), it)) - 1;
  const cv::Point2f a (contour[segment % contour.size ()]);
  const cv::Point2f b (contour[(segment + 1) % contour.size ()]);
  const double length = arc[segment + 1] - arc[segment];
  const float t = length > 0 ? static_cast<float> ((s - arc[segment]) / length) : 0.f;
  return a + (b - a) * t;
}
}  // namespace

std::string
contourLandmarkName (int index)
{
  char name[8];
  std::snprintf (name, sizeof (name), "%03d", index);
  return name;
}

int
contourLandmarkIndex (const std::string &name)
{
  if (name.size () != 3 || !std::all_of (name.begin (), name.end (), [] (char c) { return c >= '0' && c <= '9'; }))
    return -1;
  const int index = std::stoi (name);
  return index < kContourLandmarkCount ? index : -1;
}

int
mirroredContourLandmark (int index)
{
  return (kContourLandmarkCount - index) % kContourLandmarkCount;
}

cv::Rect
squareBox (const cv::Rect &box)
{
  const int side = std::max (box.width, box.height);
  return cv::Rect (box.x + box.width / 2 - side / 2, box.y + box.height / 2 - side / 2, side, side);
}

namespace
{
// The body's axes (up from the hints, right perpendicular to it on screen), its extent along
// them and its centre (of area, which the trunk dominates, not of the outline, which the limbs
// do), from the outline.
struct BodyAxes
{
  cv::Point2f up, right, centroid{0.f, 0.f};
  float top = -std::numeric_limits<float>::max (), bottom = std::numeric_limits<float>::max (), height = 1.f;

  float heightOf (const cv::Point2f &p) const { return dot (p, up); }
  float lateralOf (const cv::Point2f &p) const { return dot (p, right); }
  /** Sideways offset from the body's centre line, positive to screen right. */
  float sideOf (const cv::Point2f &p) const { return lateralOf (p) - lateralOf (centroid); }
};

BodyAxes
bodyAxes (const std::vector<cv::Point> &contour, const cv::Point2f &hint_up)
{
  BodyAxes body;
  body.up = normalised (hint_up, cv::Point2f (0.f, -1.f));
  body.right = cv::Point2f (-body.up.y, body.up.x);  // screen right for an upright body
  for (const cv::Point &p : contour)
  {
    body.top = std::max (body.top, body.heightOf (p));
    body.bottom = std::min (body.bottom, body.heightOf (p));
    body.centroid += cv::Point2f (p);
  }
  body.centroid *= 1.f / contour.size ();
  const cv::Moments area = cv::moments (contour);
  if (std::abs (area.m00) > 1.0)
    body.centroid = cv::Point2f (static_cast<float> (area.m10 / area.m00), static_cast<float> (area.m01 / area.m00));
  body.height = std::max (body.top - body.bottom, 1.f);
  return body;
}

// Step 1. Unlabelled extremities labelled by position: the one nearest the top is the head when
// it is high enough, the lowest two below the middle are feet, the rest hands. Labelled hints
// take precedence.
ContourAnchors
labelExtremities (const ContourAnchors &anchors, const BodyAxes &body)
{
  ContourAnchors hints = anchors;
  if (anchors.extremities.empty ())
    return hints;
  std::vector<cv::Point2f> rest = anchors.extremities;
  std::sort (rest.begin (), rest.end (),
             [&] (const cv::Point2f &a, const cv::Point2f &b) { return body.heightOf (a) > body.heightOf (b); });
  if (!known (hints.head))
  {
    // Raised hands can be higher than the head: of the extremities near the top, the head is
    // the one nearest the body's middle.
    auto head = rest.end ();
    for (auto it = rest.begin (); it != rest.end () && body.top - body.heightOf (*it) < 0.25f * body.height; ++it)
      if (head == rest.end () || std::abs (body.sideOf (*it)) < std::abs (body.sideOf (*head)))
        head = it;
    if (head != rest.end ())
    {
      hints.head = *head;
      rest.erase (head);
    }
  }
  const float middle = body.bottom + 0.5f * body.height;
  std::vector<cv::Point2f> feet, hands;
  for (auto it = rest.rbegin (); it != rest.rend (); ++it)
    (feet.size () < 2 && body.heightOf (*it) < middle - 0.2f * body.height ? feet : hands).push_back (*it);
  if (hints.feet.empty ())
    hints.feet = feet;
  if (hints.hands.empty ())
    for (const cv::Point2f &hand : hands)
      if (hints.hands.size () < 2)
        hints.hands.push_back (hand);
  return hints;
}

// Step 2. The top of the head: the highest outline point near the head hint; without one, the
// highest point within the body's central band (a raised hand is higher than the head but off
// to the side), else the highest point.
int
findHeadTop (const std::vector<cv::Point> &contour, const cv::Point2f &hint, const BodyAxes &body, float head_band,
             bool &from_hint)
{
  auto height = [&] (const cv::Point2f &p) { return body.heightOf (p); };
  from_hint = false;
  if (known (hint))
  {
    const float radius = 0.12f * body.height;  // about a head; wider would reach raised hands
    const int head = argmaxOnContour (contour, height, [&] (int i) { return cv::norm (cv::Point2f (contour[i]) - hint) < radius; });
    if (head >= 0)
    {
      from_hint = true;
      return head;
    }
  }
  const int central = argmaxOnContour (contour, height, [&] (int i) {
    return std::abs (body.sideOf (contour[i])) < head_band * body.height;
  });
  return central >= 0 ? central : argmaxOnContour (contour, height, [] (int) { return true; });
}

// Step 3. Hints snapped to the outline, as positions counter-clockwise from the head top (at
// most the first and the last two); hints farther than max_distance from it are dropped.
std::vector<int>
snapToOutline (const std::vector<cv::Point> &contour, const std::vector<cv::Point2f> &points, float max_distance)
{
  std::vector<int> positions;
  for (const cv::Point2f &p : points)
  {
    if (!known (p))
      continue;
    float distance = 0.f;
    const int index = nearestContourIndex (contour, p, &distance);
    if (distance <= max_distance && index > 0)
      positions.push_back (index);
  }
  std::sort (positions.begin (), positions.end ());
  if (positions.size () > 2)
    positions = {positions.front (), positions.back ()};
  return positions;
}

// Step 4. The feet: the hints, else the lowest outline points on the screen-left and
// screen-right of the body (a single known foot is kept on the side it lies on). False when the
// outline has no point below the middle.
bool
findFeet (const std::vector<cv::Point> &contour, const BodyAxes &body, const std::vector<int> &feet, int &left,
          int &right)
{
  auto lowest_on_side = [&] (float side) {
    return argmaxOnContour (
      contour, [&] (const cv::Point2f &p) { return -body.heightOf (p) + 0.3f * side * body.sideOf (p); },
      [&] (int i) { return i > 0 && body.heightOf (contour[i]) < body.heightOf (body.centroid); });
  };
  if (feet.size () == 2)
  {
    left = feet[0];
    right = feet[1];
    return true;
  }
  left = lowest_on_side (-1.f);
  right = lowest_on_side (1.f);
  if (feet.size () == 1)
    (std::abs (feet[0] - left) < std::abs (feet[0] - right) ? left : right) = feet[0];
  return left >= 0 && right >= 0;
}

// Step 5. A hand without a hint. An arm held out is its farthest point sideways above the hips,
// when that point lies more than params.hand_spread body heights out from the centre line;
// otherwise (arms down, or merged with a coat) the hand is taken to be at the wrist's height: the
// first outline point, going from the head top down that side, params.wrist_drop body heights
// below the top. from..to is the side's stretch of the outline (head top to foot).
int
findHandWithoutHint (const std::vector<cv::Point> &contour, const BodyAxes &body, const ContourAnnotationParams &params,
                     int from, int to, float side)
{
  const int out = argmaxOnContour (
    contour, [&] (const cv::Point2f &p) { return side * body.sideOf (p); },
    [&] (int i) { return i > from && i < to && body.heightOf (contour[i]) > body.heightOf (body.centroid) - 0.25f * body.height; });
  if (out >= 0 && side * body.sideOf (contour[out]) > params.hand_spread * body.height)
    return out;
  const float wrist = body.top - params.wrist_drop * body.height;
  const int n = static_cast<int> (contour.size ());
  // Screen left runs forwards from the head top, screen right backwards from its end.
  for (int step = 1; step < to - from; ++step)
  {
    const int i = side < 0 ? from + step : to - step;
    if (i > 0 && i < n && body.heightOf (contour[i]) <= wrist)
      return i;
  }
  return out;
}

// Step 6. Both hands: the hints, else findHandWithoutHint on each side (a single known hand
// replaces the guess on its side of the feet).
void
findHands (const std::vector<cv::Point> &contour, const BodyAxes &body, const ContourAnnotationParams &params,
           const std::vector<int> &hands, int foot_left, int foot_right, int &left, int &right)
{
  const int n = static_cast<int> (contour.size ());
  if (hands.size () == 2)
  {
    left = hands[0];
    right = hands[1];
    return;
  }
  left = findHandWithoutHint (contour, body, params, 0, std::min (foot_left, foot_right), -1.f);
  right = findHandWithoutHint (contour, body, params, std::max (foot_left, foot_right), n, 1.f);
  if (hands.size () == 1)
    (hands[0] < foot_left ? left : right) = hands[0];
  if (left < 0)
    left = std::max (1, std::min (foot_left, foot_right) / 2);
  if (right < 0)
    right = (std::max (foot_left, foot_right) + n) / 2;
}

// Step 7. Anchors in contour order (sorted when the hints were not) and pushed apart so that
// every segment has some length. False when the outline is too short for them.
bool
orderAnchors (std::array<int, kContourAnchorCount> &order, int n, bool &reordered)
{
  reordered = !std::is_sorted (order.begin (), order.end ());
  if (reordered)
    std::sort (order.begin (), order.end ());
  const int min_gap = std::max (1, n / (4 * kContourLandmarkCount));
  for (int k = 1; k < kContourAnchorCount; ++k)
    order[k] = std::max (order[k], order[k - 1] + min_gap);
  return order.back () < n - min_gap;
}

// Step 8. kLandmarksPerSegment landmarks per segment, evenly by arc length.
std::vector<cv::Point2f>
sampleLandmarks (const std::vector<cv::Point> &contour, const std::array<int, kContourAnchorCount> &order)
{
  const int n = static_cast<int> (contour.size ());
  std::vector<double> arc (n + 1, 0.0);
  for (int i = 0; i < n; ++i)
    arc[i + 1] = arc[i] + cv::norm (contour[(i + 1) % n] - contour[i]);
  std::vector<cv::Point2f> landmarks;
  landmarks.reserve (kContourLandmarkCount);
  for (int k = 0; k < kContourAnchorCount; ++k)
  {
    const double start = arc[order[k]];
    const double end = k + 1 < kContourAnchorCount ? arc[order[k + 1]] : arc[n];
    for (int j = 0; j < kLandmarksPerSegment; ++j)
      landmarks.push_back (pointAtArcLength (contour, arc, start + (end - start) * j / kLandmarksPerSegment));
  }
  return landmarks;
}
}  // namespace

ContourAnnotation
annotateContour (const cv::Mat &mask, const ContourAnchors &anchors, const ContourAnnotationParams &params)
{
  ContourAnnotation result;
  if (mask.empty () || mask.type () != CV_8UC1)
  {
    result.problem = "the mask must be a non-empty 8-bit single-channel image";
    return result;
  }
  std::vector<cv::Point> contour = largestOuterContour (mask, params, result.problem);
  if (contour.size () < static_cast<std::size_t> (kContourLandmarkCount) / 4)
  {
    if (result.problem.empty ())
      result.problem = "outline too short";
    return result;
  }
  const int n = static_cast<int> (contour.size ());
  const BodyAxes body = bodyAxes (contour, anchors.up);
  const ContourAnchors hints = labelExtremities (anchors, body);
  bool head_from_hint = false;
  const int head = findHeadTop (contour, hints.head, body, params.head_band, head_from_hint);
  std::rotate (contour.begin (), contour.begin () + head, contour.end ());
  result.anchor_from_hint[0] = head_from_hint;

  const float max_hint_distance = params.max_hint_distance * body.height;
  const std::vector<int> hands = snapToOutline (contour, hints.hands, max_hint_distance);
  const std::vector<int> feet = snapToOutline (contour, hints.feet, max_hint_distance);
  int foot_left = -1, foot_right = -1;
  if (!findFeet (contour, body, feet, foot_left, foot_right))
  {
    result.problem = "no feet found on the outline";
    return result;
  }
  result.anchor_from_hint[2] = !feet.empty ();
  result.anchor_from_hint[3] = feet.size () == 2;
  int hand_left = -1, hand_right = -1;
  findHands (contour, body, params, hands, foot_left, foot_right, hand_left, hand_right);
  result.anchor_from_hint[1] = !hands.empty ();
  result.anchor_from_hint[4] = hands.size () == 2;

  std::array<int, kContourAnchorCount> order{0, hand_left, foot_left, foot_right, hand_right};
  if (!orderAnchors (order, n, result.anchors_reordered))
  {
    result.problem = "outline too short for its anchors";
    return result;
  }
  result.landmarks = sampleLandmarks (contour, order);
  result.anchor_contour_index = order;
  result.tight_box = cv::boundingRect (contour);
  result.box = squareBox (result.tight_box);
  result.contour = std::move (contour);
  result.ok = true;
  return result;
}

ContourAnchors
anchorsFromCocoKeypoints (const std::vector<cv::Point3f> &keypoints)
{
  ContourAnchors anchors;
  if (keypoints.size () != 17)
    return anchors;
  auto visible = [&] (int i) { return keypoints[i].z > 0; };
  auto at = [&] (int i) { return cv::Point2f (keypoints[i].x, keypoints[i].y); };
  auto mean_of = [&] (std::initializer_list<int> ids) {
    cv::Point2f sum (0.f, 0.f);
    int count = 0;
    for (int i : ids)
      if (visible (i))
      {
        sum += at (i);
        ++count;
      }
    return count ? sum * (1.f / count) : cv::Point2f (ContourAnchors::kUnknown, ContourAnchors::kUnknown);
  };
  anchors.head = mean_of ({0, 1, 2, 3, 4});
  const cv::Point2f shoulders = mean_of ({5, 6}), hips = mean_of ({11, 12});
  const cv::Point2f upper = known (anchors.head) ? anchors.head : shoulders;
  const cv::Point2f lower = known (hips) ? hips : shoulders;
  if (known (upper) && known (lower) && upper != lower)
    anchors.up = normalised (upper - lower, anchors.up);
  // Hand tips lie beyond the wrist along the forearm, toes beyond the ankle along the shin.
  for (const auto &[end, middle, reach, list] :
       {std::make_tuple (9, 7, 0.4f, &anchors.hands), std::make_tuple (10, 8, 0.4f, &anchors.hands),
        std::make_tuple (15, 13, 0.15f, &anchors.feet), std::make_tuple (16, 14, 0.15f, &anchors.feet)})
    if (visible (end))
      list->push_back (visible (middle) ? at (end) + (at (end) - at (middle)) * reach : at (end));
  return anchors;
}

cv::Mat
maskFromPolygons (const cv::Size &size, const std::vector<std::vector<float>> &polygons)
{
  cv::Mat mask = cv::Mat::zeros (size, CV_8UC1);
  std::vector<std::vector<cv::Point>> rings;
  for (const auto &polygon : polygons)
  {
    std::vector<cv::Point> ring;
    for (std::size_t i = 0; i + 1 < polygon.size (); i += 2)
      ring.emplace_back (static_cast<int> (std::lround (polygon[i])), static_cast<int> (std::lround (polygon[i + 1])));
    if (ring.size () >= 3)
      rings.push_back (std::move (ring));
  }
  if (!rings.empty ())
    cv::fillPoly (mask, rings, cv::Scalar (255));
  return mask;
}

double
meanDistanceToClosedPolyline (const std::vector<cv::Point2f> &points, const std::vector<cv::Point2f> &outline)
{
  if (points.empty () || outline.empty ())
    return 0.0;
  double sum = 0.0;
  for (const cv::Point2f &p : points)
  {
    double best = std::numeric_limits<double>::max ();
    for (std::size_t i = 0; i < outline.size (); ++i)
    {
      const cv::Point2f a = outline[i], b = outline[(i + 1) % outline.size ()];
      const cv::Point2f ab = b - a;
      const float length2 = dot (ab, ab);
      const float t = length2 > 0 ? std::clamp (dot (p - a, ab) / length2, 0.f, 1.f) : 0.f;
      best = std::min (best, cv::norm (p - (a + ab * t)));
    }
    sum += best;
  }
  return sum / points.size ();
}
}  // namespace agex

#pragma once

#include <pcl/PointIndices.h>
#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace agex
{
/** What agex::PersonSegmentation found out about one person. Heights are metres above
  * the floor; without a floor (the fallback rule) they are measured along the up axis from
  * an arbitrary origin, so only their differences mean something. */
struct PersonInfo
{
  /** Bits of `border`: the image borders the person touches (a partly visible person). */
  enum Border : unsigned
  {
    kLeft = 1u,
    kRight = 2u,
    kTop = 4u,
    kBottom = 8u
  };

  int points = 0;                                      ///< full-resolution pixels
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero (); ///< camera frame, metres
  Eigen::Vector3f ground = Eigen::Vector3f::Zero ();   ///< the centroid dropped onto the floor (fallback: the centroid)
  float distance = 0.f;     ///< median depth z of the person's surface, metres
  float top = 0.f;          ///< height of the highest point
  float bottom = 0.f;       ///< height of the lowest point
  float width = 0.f;        ///< horizontal extent of the body's upright parts (see setMaxWidth)
  float area = 0.f;         ///< visible surface, square metres, as seen by the camera
  float hand_pixels = 0.f;  ///< pixels a hand covers at this distance (see setMinHandPixels)
  bool too_far = false;     ///< hand_pixels below the minimum: too few pixels to find hands
  bool on_floor = false;    ///< judged against a floor plane (false: by the floor-free rule)
  bool split = false;       ///< cut out of a cluster that held several people
  int pieces = 1;           ///< clusters (pieces split off by depth gaps) merged into it
  bool hidden = false;      ///< seen only in pieces behind a nearer person (not judged by the person rules)
  unsigned border = 0;      ///< Border bits
};

namespace detail
{
// The steps' shared state and working types, defined in impl/person_segmentation.hpp.
struct PersonScan;
struct PersonGridCell;
struct PersonPart;
struct PersonPartStats;
struct PersonCandidate;
struct PersonCut;
struct PersonBlocks;
struct PersonPixels;
enum class PersonVerdict;
}  // namespace detail

/** \brief Finds the people in an organized depth frame: one pcl::PointIndices per person.
  *
  * The input is an organized cloud, raw or already cleaned (mixed pixels removed,
  * denoised, floor removed). The steps (doc/pipeline.md, "People"):
  *
  * 1. **Coarse grid.** Candidates are found on one point per step x step block of pixels
  *    (setCoarseStep; by default cells 2 cm across per metre of depth whatever the
  *    resolution: step 11 at 640x480, 4 at 144x176). The people's own pixels are taken at
  *    full resolution at the end.
  * 2. **Floor.** The plane given with setFloorPlane (n.p + d = height above the floor, as
  *    agex::FloorRemoval::getFloorPlane returns it), or else agex::FloorRemoval run on the
  *    cells whose surface faces up (within the tilt limit and 20 degrees more; a few
  *    dozen cells are enough, a far floor shows in a few rows of them), and kept only if
  *    its inliers spread over an area (setMinFloorSpread) and at most a quarter as many
  *    cells lie under it (level tops of a body have the body under them). Points less than
  *    the floor margin, max(floor distance, 3 noise(z) H / z), above it are nobody's but the
  *    feet (8.): a depth error moves a point along its viewing ray, which changes the height
  *    of a point H below the camera by H / z of it.
  * 3. **Clusters.** 8-neighbour cells are connected when their depths differ by less than
  *    a gap that grows with depth: max(min gap, slope * spacing + 3 noise(z)), where
  *    spacing = step z / f is the distance between the cells on a surface facing the
  *    camera, the slope lets surfaces turned up to atan(slope) away from the camera stay
  *    connected, and noise(z) = c z^2 is the sensor's depth noise (a Kinect measures
  *    disparity, so its depth error grows with the square of the depth).
  * 4. **Person-like clusters.** With a floor: the top between the height limits; the
  *    lowest point at most the maximum bottom height, and the lowest cells standing on
  *    something (the floor, a gap in the data, the image border, or something nearer that
  *    hides the rest: not on a surface behind them, like a thing on a wall); the visible
  *    area at least the minimum (cut by the image's border: the hidden person's minimum); the upright parts at most the maximum width; at least the
  *    minimum background fraction of the outline (away from the image border) bordering
  *    on background (no data, the floor, or surfaces farther away: a fragment hemmed in by
  *    nearer things is no one of its own); a top narrower than the body (setCrownLimits),
  *    unless the top is cut off by the image or hidden behind something nearer. Walls and
  *    shelves are too wide or too tall, desks too low, chairs and cabinets as wide on top
  *    as below. Sitting people
  *    (top 1.2-1.4 m), children from 0.9 m, people behind a desk (seen from the desk top
  *    up) and people cut off by the image's borders are kept.
  * 5. **Split.** A cluster's height profile across the view (the highest point per bin) is
  *    searched for heads, as pcl::people::HeadBasedSubclustering does: peaks at least the
  *    minimum head distance apart with a valley at least the minimum valley depth below
  *    the lower one, each standing on a body (the column under it at least half as tall
  *    as the tallest column: a raised fist's is only the forearm). The cut goes where the
  *    cluster is least tall between the peaks (cells per image column), and only if it
  *    narrows there to at most the maximum narrowing of the taller column on either side
  *    (a cut between two bodies crosses only what joins them, a cut between a raised hand
  *    and the head crosses the torso) and both sides are person-like on their own.
  * 6. **Merge.** Two person-like pieces of different clusters whose ground positions are
  *    within the merge distance join when together they are person-like (a person cut in
  *    two by something in front); so do two pieces that are nobody alone (too small, too
  *    low or floating) and lie one above the other as seen from the camera (the upper body
  *    above something in front, the legs below it; with a floor only). A piece that is not
  *    person-like, at most half as large
  *    as the person and not wider than half the maximum width (an arm or hand separated by
  *    a depth gap, a leg seen below a chair) joins the nearest person, within the merge
  *    reach on the floor, that it touches in the image or lies in front of or behind
  *    (overlapping directions from the camera), unless it reaches above the person's top.
  *    **Hidden persons** (with a floor; setHiddenPersons): the pieces left over that are
  *    nobody alone (too small, too low or floating), at most half the maximum width and not
  *    above the maximum top, and that touch a person in the image while lying behind it
  *    (their mean depth beyond the person's by more than the merge distance), are a person
  *    seen round a nearer one: pieces within the merge reach of each other on the floor
  *    together, kept when together they have the hidden person's minimum area, reach the
  *    minimum top and pass the background rule (a panel seen between two people, hemmed in
  *    by them, is no one). The other person rules cannot judge so little of a body;
  *    PersonInfo::hidden marks such persons.
  * 7. **Without a floor** (none given, none found: close-range upper bodies): heights are
  *    taken along the up axis from an arbitrary origin; a cluster is a person when it has
  *    the minimum area, spans at least the fallback's minimum upright extent and at most
  *    the maximum top, and passes the width, background and narrow-top rules (so: clusters
  *    of person-like size in front of the background).
  * 8. **Full resolution.** A pixel in the block of a person's cell, or of a free cell next
  *    to one, is the person's when its depth lies within the gap of the depths of the
  *    person's cells around it (and above the floor margin, or, with setFloorContact, the
  *    feet, above the floor under the person and right under a pixel of the person:
  *    kMinFootHeight; and on its side of a cut). It is a test per pixel: following connections pixel by pixel is left to the
  *    surface segmentation that runs on the persons' pixels anyway.
  *
  * "Too far" (getTooFar): a hand of the hand area at the person's distance covers
  * hand_area * fx * fy / z^2 pixels; below the minimum hand pixels the detector has too few
  * to find hands (agex::BodyPartDetector then reports the person's head and feet only).
  * Focal lengths are estimated from the cloud (u = fx x / z + cx) unless given with
  * setFocalLength.
  *
  * Persons come out largest first (ties: lowest first index), each with its indices in
  * increasing order. Misuse (unorganized input, parameters out of range, a non-finite or
  * zero floor normal) is reported with PCL_ERROR and gives no persons; empty and all-NaN
  * frames give no persons without complaint.
  */
template <typename PointT>
class PersonSegmentation : public pcl::PCLBase<PointT>
{
  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::fake_indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

public:
  using PointCloud = pcl::PointCloud<PointT>;
  using Ptr = pcl::shared_ptr<PersonSegmentation<PointT>>;
  using ConstPtr = pcl::shared_ptr<const PersonSegmentation<PointT>>;
  /** Label of points that belong to no person. */
  static constexpr std::uint32_t kUnlabelled = std::numeric_limits<std::uint32_t>::max ();

  /** \brief Uses this floor (n.p + d = height above the floor, as
    * agex::FloorRemoval::getFloorPlane gives it; any scale is normalised, and a normal
    * pointing away from the up axis is turned round) instead of searching for one. Give it
    * whenever the floor's points are already gone (NaN) from the input: without them none
    * is found and the floor-free rule applies. */
  void setFloorPlane (const Eigen::Vector4f &plane)
  {
    given_floor_ = plane;
    floor_given_ = true;
  }
  /** Searches for the floor again (the default). */
  void resetFloorPlane () { floor_given_ = false; }
  /** Whether the last segment () had a floor (given or found). */
  bool getFloorFound () const { return floor_found_; }
  /** The floor of the last segment () (normalised; zero when there was none). */
  const Eigen::Vector4f &getFloorPlane () const { return floor_plane_; }

  /** The world's up direction in the cloud's axes (default (0, -1, 0)); the floor search
    * looks for planes facing it and the floor-free rule measures heights along it. */
  void setUpAxis (const Eigen::Vector3f &up) { up_ = up; }
  const Eigen::Vector3f &getUpAxis () const { return up_; }
  /** Largest floor tilt from the up axis, degrees (default 45: a camera looking down at people
    * from a robot or a shelf is often pitched 30-40 degrees). */
  void setFloorMaxTilt (float degrees) { floor_max_tilt_deg_ = degrees; }
  float getFloorMaxTilt () const { return floor_max_tilt_deg_; }
  /** Floor inlier distance for the search, and the least floor margin: points lower than
    * max(this, 3 noise(z) H / z) above the floor, H their height below the camera, belong
    * to nobody (but the feet with setFloorContact; default 0.04 m). */
  void setFloorDistance (float metres) { floor_distance_ = metres; }
  float getFloorDistance () const { return floor_distance_; }
  /** A plane found is the floor only if its inliers spread over an area: the smaller
    * standard deviation of their positions on it at least this (default 0.15 m; a strip
    * such as the lower edge of a torso cut off by the image has a few centimetres). */
  void setMinFloorSpread (float metres) { min_floor_spread_ = metres; }
  float getMinFloorSpread () const { return min_floor_spread_; }
  /** Fewest upward-facing cells the floor search runs on (a floor seen only far away, 4-6 m,
    * shows in a few rows of cells; the spread rule and the cells under the plane judge it). */
  static constexpr int kMinFloorCells = 16;
  /** Below the floor margin, a person's pixels (the feet) are those above the floor under the
    * person (the median height of the floor cells among its blocks) by at least three times
    * their height noise and at least this, metres. */
  static constexpr float kMinFootHeight = 0.01f;
  /** Whether pixels below the floor margin may be the person's feet (the rule of
    * kMinFootHeight; default false). Off, the floor margin takes the shoes' lowest few
    * centimetres; on, they stay, but on the Bonn keyframes at 640x480 the first five AGEX
    * extrema then reach a foot tip in 0.58 of the feet instead of 0.77 (the kept strip along
    * the floor contact draws the geodesic extremum off the toe), so it is off until the
    * detector's stages gain from it (doc/pipeline.md, "People"). */
  void setFloorContact (bool keep) { floor_contact_ = keep; }
  bool getFloorContact () const { return floor_contact_; }

  /** Focal lengths in pixels; 0 (default): estimated from the cloud. Given or estimated, a
    * focal length outside kMinFocalLength to kMaxFocalLength (agex/common/focal_length.h; a
    * cloud whose points are not a camera's at metric scale) gives no persons and a PCL_ERROR. */
  void setFocalLength (float fx, float fy)
  {
    fx_ = fx;
    fy_ = fy;
  }
  float getFocalLengthX () const { return fx_; }
  float getFocalLengthY () const { return fy_; }
  /** The focal lengths the last segment () used. */
  float getUsedFocalLengthX () const { return used_fx_; }
  float getUsedFocalLengthY () const { return used_fy_; }

  /** Angle a coarse cell spans by default: 2 cm per metre of depth, so that cost and what
    * the cells resolve do not depend on the resolution (step 11 at 640x480 with f = 525,
    * 4 at 144x176 with f = 210: 1,600-3,100 cells). */
  static constexpr float kAutoCellAngle = 0.02f;
  /** Coarse grid step in pixels; 0 (default): kAutoCellAngle times the focal length. */
  void setCoarseStep (int pixels) { coarse_step_ = pixels; }
  int getCoarseStep () const { return coarse_step_; }
  /** The step the last segment () used. */
  int getUsedCoarseStep () const { return used_step_; }

  /** Depth noise coefficient c of noise(z) = c z^2, 1/m (default 0.0015: Kinect's depth
    * error, 1.4 mm at 1 m, 3.6 cm at 5 m). */
  void setDepthNoise (float c) { depth_noise_ = c; }
  float getDepthNoise () const { return depth_noise_; }
  /** Depth change per unit of spacing that still connects neighbours (default 3: surfaces
    * turned up to 72 degrees from the camera). */
  void setMaxSurfaceSlope (float slope) { max_slope_ = slope; }
  float getMaxSurfaceSlope () const { return max_slope_; }
  /** Smallest connection gap, metres (default 0.02). */
  void setMinGap (float metres) { min_gap_ = metres; }
  float getMinGap () const { return min_gap_; }

  /** Range for the top of a person above the floor, metres (default 0.9 to 2.4: a child or
    * a seated adult to an adult's raised hands). */
  void setHeightLimits (float min_top, float max_top)
  {
    min_top_ = min_top;
    max_top_ = max_top;
  }
  float getMinTop () const { return min_top_; }
  float getMaxTop () const { return max_top_; }
  /** A person's lowest visible point is at most this high (default 1.1 m: a person behind a
    * desk shows from the desk top up); not applied at the image's bottom border. */
  void setMaxBottom (float metres) { max_bottom_ = metres; }
  float getMaxBottom () const { return max_bottom_; }
  /** Largest width of a person's upright parts (default 1.2 m). Width is the extent, along
    * either horizontal axis of the floor (across and along the view), of the bins in which
    * the cluster spans at least 0.3 m in height: arms held out do not widen a person, a
    * wall or a desk seen from its end does. */
  void setMaxWidth (float metres) { max_width_ = metres; }
  float getMaxWidth () const { return max_width_; }
  /** Least visible area, square metres (default 0.12: a head and shoulders with the chest). A
    * cluster cut by the image's border needs only the hidden person's least area
    * (setHiddenPersons, 0.06): a close body cut at the chest shows little more than its head. */
  void setMinArea (float square_metres) { min_area_ = square_metres; }
  float getMinArea () const { return min_area_; }
  /** The narrow-top rule: the crown, the cells within drop metres (plus twice the height
    * noise there, the depth noise times the top's height above the camera over its depth) of
    * the top, spans across the view without a gap at most ratio times the width
    * of the upright parts across the view (defaults 0.05 m and 0.75). A head is narrower
    * than the shoulders and hips below it (with hands on it too, 0.45 m against 0.65 m;
    * raised hands count each on their own; seen from the side, the head's 0.2 m against the
    * body's 0.3 m); a chair's back, a cabinet, a table, a lamp are as wide on top as below
    * or wider, also when cut off by the image's side or seen from the side. A crown at most
    * min_width across (default 0.25 m, plus one bin of the measurement) is a head's whatever
    * the width below it: a slim person seen from the side (the head's 0.2 m against a
    * 0.25 m body) or bent forward. */
  void setCrownLimits (float drop, float ratio, float min_width = 0.25f)
  {
    crown_drop_ = drop;
    max_crown_ratio_ = ratio;
    min_crown_width_ = min_width;
  }
  float getCrownDrop () const { return crown_drop_; }
  float getMaxCrownRatio () const { return max_crown_ratio_; }
  float getMinCrownWidth () const { return min_crown_width_; }
  /** Splitting: heads at least distance apart, with a valley at least depth below the lower,
    * and a cut column at most narrowing times as tall as the taller column on each side
    * (defaults 0.3 m, as pcl::people::HeadBasedSubclustering, 0.15 m and 0.7). */
  void setSplitLimits (float head_distance, float valley_depth, float narrowing = 0.7f)
  {
    min_head_distance_ = head_distance;
    min_valley_depth_ = valley_depth;
    max_narrowing_ = narrowing;
  }
  float getMinHeadDistance () const { return min_head_distance_; }
  float getMinValleyDepth () const { return min_valley_depth_; }
  float getMaxNarrowing () const { return max_narrowing_; }
  /** Merging: a small piece joins a person within reach on the floor (default 0.6 m, an
    * arm's length); two person-like pieces join within distance (default 0.3 m). */
  void setMergeLimits (float reach, float distance)
  {
    merge_reach_ = reach;
    merge_distance_ = distance;
  }
  float getMergeReach () const { return merge_reach_; }
  float getMergeDistance () const { return merge_distance_; }
  /** Least upright extent of a person without a floor (default 0.3 m), and least fraction
    * of a person's outline that borders on background, with or without a floor (0.5). */
  void setFallbackLimits (float min_extent, float background_fraction)
  {
    fallback_min_extent_ = min_extent;
    min_background_fraction_ = background_fraction;
  }
  float getFallbackMinExtent () const { return fallback_min_extent_; }
  float getMinBackgroundFraction () const { return min_background_fraction_; }
  /** "Too far": a hand of area square metres (default 0.01, a hand seen at an angle) must
    * cover at least pixels pixels (default 16, a patch of 4 x 4: fewer hold no hand shape). */
  void setHandLimits (float area, float pixels)
  {
    hand_area_ = area;
    min_hand_pixels_ = pixels;
  }
  float getHandArea () const { return hand_area_; }
  float getMinHandPixels () const { return min_hand_pixels_; }
  /** Whether to keep persons seen only in pieces behind a nearer person (default true), and
    * the least visible area of such a person (default 0.06 m^2: a head and shoulders). */
  void setHiddenPersons (bool find, float min_area)
  {
    find_hidden_ = find;
    hidden_min_area_ = min_area;
  }
  bool getFindHiddenPersons () const { return find_hidden_; }
  float getHiddenPersonMinArea () const { return hidden_min_area_; }

  /** \brief Finds the persons. Empty on error. */
  void segment (std::vector<pcl::PointIndices> &persons);
  /** \brief Finds the persons and labels every input point with its person's index
    * (kUnlabelled for points of nobody). */
  void segment (pcl::PointCloud<pcl::Label> &labels, std::vector<pcl::PointIndices> &persons);

  /** Per person of the last segment (), in the same order. */
  const std::vector<PersonInfo> &getPersons () const { return infos_; }
  /** Per person of the last segment (): too far for its hands to have enough pixels. */
  std::vector<bool> getTooFar () const;

protected:
  std::string getClassName () const { return "PersonSegmentation"; }

private:
  bool validParameters () const;
  bool validInput () const;

  // The steps of segment (), in order (the class comment's numbers); each hands on what it
  // found in a detail::PersonScan.
  bool usable (const detail::PersonScan &scan, int i) const;
  void estimateFocalLengths (detail::PersonScan &scan) const;
  bool buildCoarseGrid (detail::PersonScan &scan) const;
  pcl::IndicesPtr levelCells (const detail::PersonScan &scan) const;
  void findFloor (detail::PersonScan &scan);
  void placeCells (detail::PersonScan &scan) const;
  void clusterCells (detail::PersonScan &scan) const;
  void findCandidates (const detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people,
                       std::vector<detail::PersonCandidate> &leftovers) const;
  float minPersonArea (const detail::PersonPartStats &s) const;
  bool splitAtHeads (const detail::PersonScan &scan, const detail::PersonPart &part,
                     const detail::PersonPartStats &s, detail::PersonPart &left, detail::PersonPart &right) const;
  std::vector<detail::PersonCut> headCuts (const detail::PersonScan &scan, const detail::PersonPartStats &s) const;
  void mergePersonLike (const detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people) const;
  bool joinedPerson (const detail::PersonScan &scan, const detail::PersonCandidate &a,
                     const detail::PersonCandidate &b, detail::PersonCandidate &both) const;
  void mergeHiddenPieces (const detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people,
                          std::vector<detail::PersonCandidate> &leftovers) const;
  void mergePieces (detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people,
                    std::vector<detail::PersonCandidate> &leftovers) const;
  int nearestPerson (const std::vector<detail::PersonPartStats> &own, const detail::PersonPartStats &piece,
                     const std::vector<unsigned char> &touches) const;
  void findHiddenPersons (detail::PersonScan &scan, std::vector<detail::PersonCandidate> &people,
                          const std::vector<detail::PersonCandidate> &leftovers) const;
  void takePixels (const detail::PersonScan &scan, const std::vector<detail::PersonCandidate> &people,
                   pcl::PointCloud<pcl::Label> &labels, std::vector<detail::PersonPixels> &pixels) const;
  void personPixels (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts, int k,
                     bool bounded, const detail::PersonBlocks &blocks, pcl::PointCloud<pcl::Label> &labels,
                     detail::PersonPixels &out) const;
  void describePersons (const detail::PersonScan &scan, const std::vector<detail::PersonCandidate> &people,
                        std::vector<detail::PersonPixels> &pixels, pcl::PointCloud<pcl::Label> &labels,
                        std::vector<pcl::PointIndices> &persons);
  PersonInfo personInfo (const detail::PersonScan &scan, const detail::PersonCandidate &person, int k,
                         const detail::PersonPixels &pixels) const;

  // The rules the steps share: connection, statistics and the verdict on a set of parts.
  float floorMargin (const detail::PersonScan &scan, float z, float h) const;
  bool connected (const detail::PersonScan &scan, const detail::PersonGridCell &a, const detail::PersonGridCell &b,
                  bool diagonal) const;
  void measure (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                detail::PersonPartStats &s) const;
  void measureBins (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                    detail::PersonPartStats &s) const;
  void countVerticalNeighbour (const detail::PersonScan &scan, const detail::PersonPart &part, int c, int rows,
                               bool no_data_counts, int &seen, int &counted) const;
  void outline (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                detail::PersonPartStats &s) const;
  detail::PersonVerdict verdict (const detail::PersonScan &scan, const std::vector<detail::PersonPart> &parts,
                                 detail::PersonPartStats &s) const;

  Eigen::Vector4f given_floor_ = Eigen::Vector4f::Zero ();
  bool floor_given_ = false;
  bool floor_found_ = false;
  Eigen::Vector4f floor_plane_ = Eigen::Vector4f::Zero ();
  Eigen::Vector3f up_ = Eigen::Vector3f (0.f, -1.f, 0.f);
  float floor_max_tilt_deg_ = 45.f;
  float floor_distance_ = 0.04f;
  float min_floor_spread_ = 0.15f;
  float fx_ = 0.f, fy_ = 0.f, used_fx_ = 0.f, used_fy_ = 0.f;
  int coarse_step_ = 0, used_step_ = 0;
  float depth_noise_ = 0.0015f;
  float max_slope_ = 3.f;
  float min_gap_ = 0.02f;
  float min_top_ = 0.9f, max_top_ = 2.4f;
  float max_bottom_ = 1.1f;
  float max_width_ = 1.2f;
  float min_area_ = 0.12f;
  float crown_drop_ = 0.05f, max_crown_ratio_ = 0.75f, min_crown_width_ = 0.25f;
  float min_head_distance_ = 0.3f, min_valley_depth_ = 0.15f, max_narrowing_ = 0.7f;
  float merge_reach_ = 0.6f, merge_distance_ = 0.3f;
  float fallback_min_extent_ = 0.3f, min_background_fraction_ = 0.5f;
  float hand_area_ = 0.01f, min_hand_pixels_ = 16.f;
  bool find_hidden_ = true;
  bool floor_contact_ = false;
  float hidden_min_area_ = 0.06f;
  std::vector<PersonInfo> infos_;
  pcl::PointCloud<pcl::Label> scratch_labels_;
};

/** \brief The person of each mesh: the label (from PersonSegmentation::segment) most of
  * its points carry, or -1 when most carry none. */
std::vector<int> personOfMeshes (const pcl::PointCloud<pcl::Label> &labels,
                                 const std::vector<pcl::PointIndices> &meshes);
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/filters/impl/person_segmentation.hpp>
#endif

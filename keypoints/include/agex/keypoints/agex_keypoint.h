#pragma once

#include <agex/common/point_types.h>
#include <agex/keypoints/bucket_queue.h>

#include <pcl/PointIndices.h>
#include <pcl/keypoints/keypoint.h>

#include <vector>

namespace agex
{
/** \brief AGEX: accumulative geodesic extrema of the surface meshes of an organized
  * depth frame (Plagemann, Ganapathi, Koller, Thrun, ICRA 2010).
  *
  * The cloud's finite points form a graph: 8-neighbour pixels are joined by an edge
  * weighted with their 3D distance when that distance is below delta_connected.
  * Each connected mesh (from setMeshes, or found with agex::SurfaceSegmentation
  * over the input indices) yields up to k points:
  *  - AGEX_1 is the mesh's geodesic centroid, approximated by the mesh vertex
  *    nearest to the mesh's 3D centroid (exact for convex patches; on a body it
  *    lands on the torso);
  *  - AGEX_k adds the vertex with the largest geodesic distance to all points
  *    found so far (ties: the lowest point index), while that distance is at least
  *    min_separation (default 0: always, up to k). The distances only shrink as points
  *    are added, so a mesh stops once its extremities are found: a small mesh (a
  *    detached hand, a strip of a sleeve) gets a few points, not k on one blob.
  * Distances to the growing set are kept by an incremental multi-source Dijkstra
  * (with a bucket queue, since edges are never longer than delta_connected):
  * each new point is joined to the source by a zero-cost edge, and only vertices
  * whose distance drops are relaxed again (Mode::Incremental). Mode::Naive reruns a
  * full multi-source Dijkstra for every k, as a reference; both give identical
  * points, order and distances.
  *
  * Orientation: from a new point, the shortest-path tree is followed back towards
  * the earlier points until the geodesic distance covered reaches delta_orient;
  * the orientation is unit(point - reached vertex), pointing outwards along a limb.
  * The centroid has no path and gets a zero orientation.
  *
  * Output: one point per interest point, meshes in order and ranks 1..k within a
  * mesh; getKeypointsIndices() gives their indices in the input cloud. With
  * agex::InterestPoint as output type every field is filled; for other types the
  * fields with matching names (x, y, z, ...) are. An unorganized input or a bad parameter
  * is an error (PCL_ERROR, no keypoint indices; pcl::Keypoint::compute leaves the output
  * untouched then); empty or all-NaN frames give an empty output.
  */
template <typename PointInT, typename PointOutT = agex::InterestPoint>
class AGEXKeypoint : public pcl::Keypoint<PointInT, PointOutT>
{
public:
  using Ptr = pcl::shared_ptr<AGEXKeypoint<PointInT, PointOutT>>;
  using ConstPtr = pcl::shared_ptr<const AGEXKeypoint<PointInT, PointOutT>>;
  using PointCloudIn = typename pcl::Keypoint<PointInT, PointOutT>::PointCloudIn;
  using PointCloudOut = typename pcl::Keypoint<PointInT, PointOutT>::PointCloudOut;

  enum class Mode
  {
    Incremental,  ///< one Dijkstra, updated for each new point (default)
    Naive         ///< a full multi-source Dijkstra per point (reference)
  };

  AGEXKeypoint () { name_ = "AGEXKeypoint"; }

  /** Points per mesh, the centroid included (default 5). */
  void setPointsPerMesh (int k) { k_per_mesh_ = k; }
  int getPointsPerMesh () const { return k_per_mesh_; }

  /** A point is added only while its geodesic distance to the points found is at least
    * this (metres, default 0: k points per mesh as long as the mesh has vertices left). */
  void setMinSeparation (float metres) { min_separation_ = metres; }
  float getMinSeparation () const { return min_separation_; }

  /** Edge length limit in metres for the geodesic graph (default 0.05). */
  void setDeltaConnected (float metres) { delta_connected_ = metres; }
  float getDeltaConnected () const { return delta_connected_; }
  /** The connection limit grows with depth as max (delta, growth z^2) (metres per square
    * metre of depth, default 0: fixed; agex::connectedNeighbours). */
  void setDeltaConnectedGrowth (float per_square_metre) { delta_connected_growth_ = per_square_metre; }
  float getDeltaConnectedGrowth () const { return delta_connected_growth_; }

  /** Geodesic distance in metres traced back for the orientation (default 0.10). */
  void setDeltaOrient (float metres) { delta_orient_ = metres; }
  float getDeltaOrient () const { return delta_orient_; }

  /** Meshes with fewer points get no interest points (default 50). */
  void setMinMeshSize (std::size_t points) { min_mesh_size_ = points; }
  std::size_t getMinMeshSize () const { return min_mesh_size_; }

  void setMode (Mode mode) { mode_ = mode; }
  Mode getMode () const { return mode_; }

  /** Use these meshes (e.g. from agex::SurfaceSegmentation) instead of segmenting
    * the input indices. Mesh ids in the output are positions in this vector. */
  void setMeshes (const std::vector<pcl::PointIndices> &meshes)
  {
    meshes_ = meshes;
    user_meshes_ = true;
  }
  /** Go back to segmenting the input indices. */
  void clearMeshes ()
  {
    meshes_.clear ();
    user_meshes_ = false;
  }
  /** The meshes used by the last compute(). */
  const std::vector<pcl::PointIndices> &getMeshes () const { return meshes_; }

protected:
  using pcl::Keypoint<PointInT, PointOutT>::name_;
  using pcl::Keypoint<PointInT, PointOutT>::input_;
  using pcl::Keypoint<PointInT, PointOutT>::indices_;
  using pcl::Keypoint<PointInT, PointOutT>::keypoints_indices_;
  using pcl::Keypoint<PointInT, PointOutT>::getClassName;

  /** Resets the last run's keypoint indices (so they are empty after an error, however
    * compute () is reached), then checks input and parameters; no search tree is needed
    * (the grid is the graph). pcl::Keypoint::compute leaves the output cloud as it was
    * when this fails. */
  bool initCompute () override;
  void detectKeypoints (PointCloudOut &output) override;

private:
  /** The geodesic graph of one mesh: vertex i is cloud point points[i]; at most 8 edges. */
  struct MeshGraph
  {
    std::vector<int> points;
    struct Edge
    {
      int target;
      float length;
    };
    std::vector<int> degree;
    std::vector<Edge> edges;  // 8 slots per vertex: one 64-byte cache line
  };

  void buildGraph (const pcl::Indices &mesh, MeshGraph &graph);
  void relax (const MeshGraph &graph);
  void runMesh (const MeshGraph &graph, int mesh_id, PointCloudOut &output);

  int k_per_mesh_ = 5;
  float delta_connected_ = 0.05f;
  float delta_connected_growth_ = 0.f;
  float max_edge_ = 0.f;  ///< the longest edge of the mesh being processed (the bucket queue's range)
  float delta_orient_ = 0.10f;
  float min_separation_ = 0.f;
  std::size_t min_mesh_size_ = 50;
  Mode mode_ = Mode::Incremental;
  std::vector<pcl::PointIndices> meshes_;
  bool user_meshes_ = false;

  // Per-mesh scratch, kept to avoid reallocating for every frame.
  std::vector<int> point_to_vertex_;
  std::vector<float> distance_;
  std::vector<int> parent_;
  BucketQueue queue_;
};
}  // namespace agex

#ifdef PCL_NO_PRECOMPILE
#include <agex/keypoints/impl/agex_keypoint.hpp>
#endif

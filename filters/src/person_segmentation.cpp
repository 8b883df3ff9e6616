#include <agex/filters/impl/person_segmentation.hpp>

#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

#include <map>

std::vector<int>
agex::personOfMeshes (const pcl::PointCloud<pcl::Label> &labels, const std::vector<pcl::PointIndices> &meshes)
{
  std::vector<int> person (meshes.size (), -1);
  std::map<std::uint32_t, std::size_t> votes;
  for (std::size_t m = 0; m < meshes.size (); ++m)
  {
    votes.clear ();
    for (const auto i : meshes[m].indices)
      if (i >= 0 && static_cast<std::size_t> (i) < labels.size ())
        ++votes[labels[i].label];
    std::size_t best = 0;
    for (const auto &vote : votes)
      if (vote.second > best)
      {
        best = vote.second;
        person[m] = vote.first == PersonSegmentation<pcl::PointXYZ>::kUnlabelled ? -1 : static_cast<int> (vote.first);
      }
  }
  return person;
}

PCL_INSTANTIATE (PersonSegmentation, (pcl::PointXYZ)(pcl::PointXYZI)(pcl::PointXYZRGBA))

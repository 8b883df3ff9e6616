// Mixed pixels of a synthetic step edge: a program that needs agex's filters and nothing else.
#include <agex/filters/mixed_pixel_filter.h>

#include <cstdio>

int
main ()
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud (new pcl::PointCloud<pcl::PointXYZ> (32, 8));
  for (int v = 0; v < 8; ++v)
    for (int u = 0; u < 32; ++u)
    {
      // A near plane (1 m) left, a far one (2 m) right, one veil pixel between them.
      const float z = u < 16 ? 1.f : (u == 16 ? 1.5f : 2.f);
      (*cloud) (u, v) = pcl::PointXYZ ((u - 16) * z / 100.f, (v - 4) * z / 100.f, z);
    }
  agex::MixedPixelFilter<pcl::PointXYZ> mixed;
  mixed.setInputCloud (cloud);
  mixed.setNegative (true);
  pcl::Indices flying;
  mixed.filter (flying);
  std::printf ("mixed pixels: %zu\n", flying.size ());
  return flying.size () == 8 ? 0 : 1;  // the veil column, one pixel per row
}

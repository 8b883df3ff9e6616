#pragma once

#include <cmath>
#include <utility>
#include <vector>

namespace agex
{
/** \brief A circular bucket queue (Dial's algorithm) for shortest paths whose edge
  * weights are positive and at most max_weight.
  *
  * Entries are grouped by floor(distance / width). Every key in the queue lies
  * within max_weight of the one being processed, so ceil(max_weight / width) + 2
  * buckets (rounded up to a power of two, to index with a mask) used circularly
  * hold them all. Within a bucket the order is arbitrary:
  * the search is label-correcting, so a vertex may be settled twice, but it ends at
  * the same distances as Dijkstra's (the least fixed point of the relaxations).
  */
class BucketQueue
{
public:
  using Entry = std::pair<float, int>;  // distance, vertex

  void reset (float width, float max_weight)
  {
    inverse_width_ = 1.f / width;
    std::size_t count = 1;
    while (count < static_cast<std::size_t> (std::ceil (max_weight / width)) + 2)
      count *= 2;
    mask_ = count - 1;
    if (buckets_.size () != count)
      buckets_.assign (count, {});
    else
      for (auto &b : buckets_)
        b.clear ();
    current_ = 0;
    size_ = 0;
  }

  bool empty () const { return size_ == 0; }

  void push (float distance, int vertex)
  {
    const auto bucket = static_cast<std::size_t> (distance * inverse_width_);
    buckets_[bucket & mask_].emplace_back (distance, vertex);
    ++size_;
  }

  /** Removes and returns an entry of the lowest non-empty bucket. */
  Entry pop ()
  {
    while (buckets_[current_ & mask_].empty ())
      ++current_;
    auto &bucket = buckets_[current_ & mask_];
    const Entry entry = bucket.back ();
    bucket.pop_back ();
    --size_;
    return entry;
  }

private:
  std::vector<std::vector<Entry>> buckets_;
  float inverse_width_ = 1.f;
  std::size_t mask_ = 0;
  std::size_t current_ = 0;
  std::size_t size_ = 0;
};
}  // namespace agex

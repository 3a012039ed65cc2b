// Step buffers that may outgrow their reserve in an extreme step (a cloth flung across itself)
// and the way back to it. Shrinking happens between steps, never inside one: the step itself
// allocates only when a list outgrows its capacity (doc/reliability.md "Soak").
#pragma once
#include <cstddef>
#include <vector>

namespace pbd_cloth {

// Gives `list` back the capacity `reserved` if it has grown beyond it and its contents fit in it
// again; the contents are kept. Returns the bytes released.
template <class T>
std::size_t shrinkToReserve(std::vector<T>& list, std::size_t reserved) {
  if (list.capacity() <= reserved || list.size() > reserved) return 0;
  const std::size_t released = (list.capacity() - reserved) * sizeof(T);
  std::vector<T> smaller;
  smaller.reserve(reserved);
  smaller.assign(list.begin(), list.end());
  list.swap(smaller);
  return released;
}

}  // namespace pbd_cloth

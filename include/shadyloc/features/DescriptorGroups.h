/* ShadyLoc — exhaustive nearest-descriptor search over many groups of
 * 256-bit binary descriptors (a map's keyframes), for the place search's
 * vote: which group holds each live descriptor's nearest neighbour.
 *
 * Exact, and the same answer as comparing every pair in order (the first
 * of equally near descriptors wins, groups in the order asked, descriptors
 * in the order added), only faster: the descriptors sit in one contiguous
 * array (a map keyframe's measurements are ~10x their descriptor's size),
 * the array is walked in blocks that stay in cache while every query meets
 * them, a comparison stops after half the bits once it cannot win, and the
 * CPU's popcount instruction is used where it has one (chosen at run time:
 * the build sets no global target flags).
 */
#pragma once

#include <shadyloc/features/Brief.h>

#include <cstdint>
#include <vector>

namespace shadyloc::features
{
class DescriptorGroups
{
   public:
	/** Appends a group (its id is the number of groups before it). */
	template <class Range, class DescriptorOf>
	void addGroup(const Range& items, DescriptorOf descriptorOf)
	{
		for (const auto& it : items) m_desc.push_back(descriptorOf(it));
		m_begin.push_back(m_desc.size());
	}
	size_t groups() const { return m_begin.size() - 1; }
	size_t descriptors() const { return m_desc.size(); }

	/** For each query, the position in `among` (group ids) of the group
	 * holding its nearest descriptor at distance <= maxDistance, or -1. */
	std::vector<int> nearestGroup(
		const std::vector<TBriefDescriptor>& queries, const std::vector<uint32_t>& among, int maxDistance) const;

	/** Whether the popcount instruction is used (for the benchmark's record). */
	static bool hardwarePopcount();

   private:
	std::vector<TBriefDescriptor> m_desc;
	std::vector<size_t> m_begin{0};	 //!< group g is [m_begin[g], m_begin[g+1])
};

}  // namespace shadyloc::features

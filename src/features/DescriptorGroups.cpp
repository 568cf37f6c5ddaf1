/* ShadyLoc — exhaustive nearest-descriptor search over groups (see the header). */
#include <shadyloc/features/DescriptorGroups.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace shadyloc::features
{
namespace
{
/** The first descriptor of [d, d + n) strictly nearer to q than `best`
 * (which it lowers), or -1. The half-way test is exact: the distance only
 * grows with the other half. */
template <int (*Popcount)(uint64_t)>
inline long scanNearest(const TBriefDescriptor* d, size_t n, const TBriefDescriptor& q, int& best)
{
	long found = -1;
	for (size_t i = 0; i < n; i++)
	{
		const auto& w = d[i].w;
		int s = Popcount(w[0] ^ q.w[0]) + Popcount(w[1] ^ q.w[1]);
		if (s >= best) continue;
		s += Popcount(w[2] ^ q.w[2]) + Popcount(w[3] ^ q.w[3]);
		if (s < best)
		{
			best = s;
			found = static_cast<long>(i);
		}
	}
	return found;
}

int swarPopcount(uint64_t x) { return popcount64(x); }

using ScanFn = long (*)(const TBriefDescriptor*, size_t, const TBriefDescriptor&, int&);

long scanPortable(const TBriefDescriptor* d, size_t n, const TBriefDescriptor& q, int& best)
{
	return scanNearest<swarPopcount>(d, n, q, best);
}

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("popcnt"))) int cpuPopcount(uint64_t x) { return __builtin_popcountll(x); }
__attribute__((target("popcnt"), flatten)) long scanPopcnt(const TBriefDescriptor* d, size_t n, const TBriefDescriptor& q, int& best)
{
	return scanNearest<cpuPopcount>(d, n, q, best);
}
bool cpuHasPopcount() { return __builtin_cpu_supports("popcnt"); }
#else
long scanPopcnt(const TBriefDescriptor* d, size_t n, const TBriefDescriptor& q, int& best)
{
	return scanPortable(d, n, q, best);
}
bool cpuHasPopcount() { return false; }
#endif

ScanFn scanner()
{
	static const ScanFn fn = cpuHasPopcount() ? scanPopcnt : scanPortable;
	return fn;
}

// Descriptors per block: 8 Ki x 32 B = 256 KiB, within a core's L2.
constexpr size_t kBlock = 8192;
}  // namespace

bool DescriptorGroups::hardwarePopcount() { return cpuHasPopcount(); }

std::vector<int> DescriptorGroups::nearestGroup(
	const std::vector<TBriefDescriptor>& queries, const std::vector<uint32_t>& among, int maxDistance) const
{
	const ScanFn scan = scanner();
	std::vector<int> best(queries.size(), maxDistance + 1), group(queries.size(), -1);
	// Consecutive groups of `among` gathered into blocks of about kBlock
	// descriptors; a group is never split, so "first of equals" holds.
	size_t a = 0;
	while (a < among.size())
	{
		const size_t a0 = a;
		size_t n = 0;
		do
		{
			if (among[a] >= groups())
				throw std::out_of_range("DescriptorGroups: no group " + std::to_string(among[a]));
			n += m_begin[among[a] + 1] - m_begin[among[a]];
			a++;
		} while (a < among.size() && n < kBlock);
		for (size_t q = 0; q < queries.size(); q++)
			for (size_t g = a0; g < a; g++)
			{
				const size_t b = m_begin[among[g]], e = m_begin[among[g] + 1];
				if (scan(m_desc.data() + b, e - b, queries[q], best[q]) >= 0) group[q] = static_cast<int>(g);
			}
	}
	return group;
}

}  // namespace shadyloc::features

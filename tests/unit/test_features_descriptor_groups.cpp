/* Tests of the place vote's nearest-descriptor search (DescriptorGroups):
 * the same answer as comparing every pair in order, ties included. */
#include <shadyloc/features/DescriptorGroups.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace shadyloc::features;

namespace
{
TBriefDescriptor randomDescriptor(std::mt19937_64& rng)
{
	TBriefDescriptor d;
	for (auto& w : d.w) w = rng();
	return d;
}

TBriefDescriptor flipBits(TBriefDescriptor d, int bits, std::mt19937_64& rng)
{
	for (int b = 0; b < bits; b++)
	{
		const auto i = rng() % 256;
		d.w[i / 64] ^= uint64_t{1} << (i % 64);
	}
	return d;
}

/** The reference: every pair, groups in `among`'s order, first of equals. */
std::vector<int> exhaustive(
	const std::vector<std::vector<TBriefDescriptor>>& groups, const std::vector<TBriefDescriptor>& queries,
	const std::vector<uint32_t>& among, int maxDistance)
{
	std::vector<int> out;
	for (const auto& q : queries)
	{
		int best = maxDistance + 1, bestA = -1;
		for (size_t a = 0; a < among.size(); a++)
			for (const auto& d : groups[among[a]])
				if (const int h = hamming(d, q); h < best) best = h, bestA = static_cast<int>(a);
		out.push_back(bestA);
	}
	return out;
}
}  // namespace

TEST(FeaturesBrief, NearestGroupIsTheExhaustiveSearchsAnswer)
{
	std::mt19937_64 rng(7);
	// About 15k descriptors in 60 groups (one empty): several cache blocks.
	std::vector<std::vector<TBriefDescriptor>> groups(60);
	for (size_t g = 0; g < groups.size(); g++)
		for (size_t i = 0, n = g == 13 ? 0 : 20 + rng() % 480; i < n; i++)
			groups[g].push_back(randomDescriptor(rng));
	// Ties: copies of some descriptors in later groups.
	for (int k = 0; k < 200; k++)
	{
		const size_t g = rng() % 30, h = 30 + rng() % 30;
		if (!groups[g].empty()) groups[h].push_back(groups[g][rng() % groups[g].size()]);
	}
	DescriptorGroups index;
	for (const auto& g : groups) index.addGroup(g, [](const TBriefDescriptor& d) { return d; });
	ASSERT_EQ(index.groups(), groups.size());

	// Queries near stored descriptors (0-60 bits away) and random ones.
	std::vector<TBriefDescriptor> queries;
	for (int k = 0; k < 400; k++)
	{
		const auto& g = groups[rng() % groups.size()];
		queries.push_back(g.empty() || k % 4 == 0 ? randomDescriptor(rng) : flipBits(g[rng() % g.size()], static_cast<int>(rng() % 61), rng));
	}
	std::vector<uint32_t> all(groups.size());
	for (uint32_t g = 0; g < all.size(); g++) all[g] = g;
	std::vector<uint32_t> some = all;
	std::shuffle(some.begin(), some.end(), rng);  // an order of its own
	some.resize(37);
	for (const auto& among : {all, some})
		for (const int maxDistance : {0, 30, 50, 256})
		{
			const auto want = exhaustive(groups, queries, among, maxDistance);
			EXPECT_EQ(index.nearestGroup(queries, among, maxDistance), want) << "max distance " << maxDistance;
			// Not vacuous: at 50 bits most near queries find their group.
			if (maxDistance == 50)
			{
				EXPECT_GT(std::count_if(want.begin(), want.end(), [](int a) { return a >= 0; }), 100);
			}
		}
	EXPECT_TRUE(index.nearestGroup(queries, {}, 50) == std::vector<int>(queries.size(), -1));
	EXPECT_THROW(index.nearestGroup(queries, {60}, 50), std::out_of_range);
}

/* ShadyLoc — blind episodes (docs/localisation.md, Definitions). */
#include <shadyloc/eval/BlindEpisodes.h>

#include <stdexcept>
#include <string>

namespace shadyloc::eval
{
const char* toString(TBlindEpisode::Kind k)
{
	switch (k)
	{
		case TBlindEpisode::Between: return "between";
		case TBlindEpisode::AtEnd: return "at_end";
		default: return "before_first_fix";
	}
}

std::vector<TBlindEpisode> blindEpisodes(const std::vector<bool>& fix, const std::vector<double>& dist)
{
	if (fix.size() != dist.size())
		throw std::invalid_argument(
			"blindEpisodes: " + std::to_string(fix.size()) + " fix flags but " + std::to_string(dist.size()) +
			" distances");
	const size_t n = fix.size();
	std::vector<TBlindEpisode> episodes;
	int lastFix = -1;
	for (size_t i = 0; i <= n; i++)
	{
		const bool isFix = i < n && fix[i];
		if (i < n && !isFix) continue;
		// i is a fix (or the end); frames lastFix+1 .. i-1 are blind.
		if (static_cast<int>(i) > lastFix + 1)
		{
			TBlindEpisode e;
			e.first = static_cast<size_t>(lastFix + 1);
			e.last = i - 1;
			const double from = lastFix >= 0 ? dist[lastFix] : dist[0];
			const double to = i < n ? dist[i] : dist[n - 1];
			e.length_m = to - from;
			e.kind = lastFix < 0 ? TBlindEpisode::BeforeFirstFix : (i == n ? TBlindEpisode::AtEnd : TBlindEpisode::Between);
			episodes.push_back(e);	// never localised: one BeforeFirstFix episode
		}
		if (i < n) lastFix = static_cast<int>(i);
	}
	return episodes;
}

}  // namespace shadyloc::eval

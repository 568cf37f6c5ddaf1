/* shadyloc apps — reading back a `shadyloc localise` output folder's
 * provenance (summary.json), for the commands that draw such folders. */
#pragma once

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace shadyloc::apps
{
/** A string of summary.json's provenance ("map", "map_fnv1a64", "live",
 * "live_fnv1a64", "gt", "gt_fnv1a64", "localisers"), "" if absent (no
 * summary.json: an older or hand-made folder). */
inline std::string localiseProvenance(const std::string& dir, const std::string& key)
{
	std::ifstream f(std::filesystem::path(dir) / "summary.json");
	std::stringstream s;
	s << f.rdbuf();
	const std::string text = s.str();
	std::smatch m;
	if (!std::regex_search(text, m, std::regex("\"" + key + "\": \"([^\"]*)\""))) return "";
	return m[1];
}
}  // namespace shadyloc::apps

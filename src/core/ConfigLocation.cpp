/* ShadyLoc — where in the config files a setting lies (see ConfigLocation.h). */
#include <shadyloc/core/ConfigLocation.h>

#include <fstream>
#include <regex>

namespace shadyloc::core
{
namespace
{
/** The line number of the setting in one file, 0 if absent. */
int lineIn(const std::string& file, const std::string& section, const std::string& key)
{
	std::ifstream in(file);
	std::string line, cur;
	int found = 0;
	for (int n = 1; std::getline(in, line); n++)
	{
		const auto b = line.find_first_not_of(" \t");
		if (b == std::string::npos || line[b] == ';' || line[b] == '#') continue;
		if (line[b] == '[')
		{
			const auto e = line.find(']', b);
			cur = e == std::string::npos ? "" : line.substr(b + 1, e - b - 1);
			if (key.empty() && cur == section && !found) found = n;
			continue;
		}
		if (key.empty() || cur != section) continue;
		const auto eq = line.find('=', b);
		std::string k = line.substr(b, eq == std::string::npos ? std::string::npos : eq - b);
		while (!k.empty() && (k.back() == ' ' || k.back() == '\t')) k.pop_back();
		if (k == key) found = n;  // the last one counts, as in the reader
	}
	return found;
}
}  // namespace

std::string locateSetting(const std::vector<std::string>& files, const std::string& section, const std::string& key)
{
	std::string where;
	for (const auto& file : files)
		if (const int n = lineIn(file, section, key)) where = file + ":" + std::to_string(n);
	return where;
}

std::string configError(const std::vector<std::string>& files, const std::string& what, const std::string& msg)
{
	// "[section] key: why" (reader errors) or "[section] option key must ..." (range checks).
	static const std::regex setting(R"(\[([A-Za-z0-9_.\-]+)\](?: (?:option )?([A-Za-z0-9_]+))?[: ])");
	std::smatch m;
	std::string where;
	if (std::regex_search(msg, m, setting))
	{
		if (m[2].matched) where = locateSetting(files, m[1], m[2]);
		if (where.empty()) where = locateSetting(files, m[1], "");
	}
	return (where.empty() ? "config " + what : where) + ": " + msg;
}

}  // namespace shadyloc::core

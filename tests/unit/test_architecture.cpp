/* ShadyLoc tests: the area graph of docs/architecture.md. Every
 * `#include <shadyloc/<area>/...>` in include/shadyloc/<a>/ and src/<a>/ must
 * name <a> itself or an area <a> may use; a new dependency is a decision to
 * write into the document (and here), not an accident. The library's top
 * level (the headers directly in include/shadyloc, the sources directly in
 * src: the public face, the class registration) is above every area: no
 * area includes it, but the face's own implementation. */
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

namespace fs = std::filesystem;

TEST(ArchitectureAreaGraph, OnlyAllowedIncludes)
{
	// docs/architecture.md, "Area graph".
	const std::map<std::string, std::set<std::string>> allowed = {
		{"image", {}},
		{"geometry", {}},
		{"io", {"geometry"}},
		{"features", {"geometry"}},
		// The channels' frame source yields the stereo model with the images.
		{"filters", {"geometry", "image", "io"}},
		{"map", {"features", "geometry", "io"}},
		// The VO's keyframes are its own type (vo/Keyframe.h); the survey joins them to the map.
		{"vo", {"features", "geometry"}},
		// Joins the VO and the map (and the channels' filters that the map records).
		{"survey", {"features", "filters", "geometry", "io", "map", "vo"}},
		// The leave-one-out evaluation surveys maps and runs the localisation;
		// a localised run's metrics and output files are eval's as well, so
		// localisation (below) needs nothing from it.
		// ... and reads the runs' cameras through the channels' frame source.
		{"eval", {"filters", "geometry", "io", "localisation", "map", "survey"}},
		{"sim", {"geometry", "io"}},
		// The exporter walks the colour frames with the channels' frame source.
		{"datasets", {"filters", "io"}},
		{"render", {"io"}},
		// The bottom floor: settings and errors, nothing above it (the class
		// registration lists filters and map, so it is at the top: src/Registration.cpp).
		{"core", {}},
		{"localisation", {"features", "filters", "geometry", "io", "map", "vo"}},
	};
	const fs::path root(SHADYLOC_SOURCE_DIR);
	const std::regex inc(R"(^\s*#\s*include\s*<shadyloc/([a-z_]+)/)");
	const std::regex top(R"(^\s*#\s*include\s*<shadyloc/([A-Za-z_]+)\.h>)");
	size_t files = 0;
	for (const auto& dir : {root / "include" / "shadyloc", root / "src"})
		for (const auto& areaDir : fs::directory_iterator(dir))
		{
			if (!areaDir.is_directory()) continue;
			const std::string area = areaDir.path().filename().string();
			if (area == "apps") continue;  // the apps wire every area
			const auto it = allowed.find(area);
			ASSERT_NE(it, allowed.end()) << "area '" << area << "' is not in docs/architecture.md's area graph";
			for (const auto& f : fs::recursive_directory_iterator(areaDir.path()))
			{
				if (!f.is_regular_file()) continue;
				files++;
				std::ifstream in(f.path());
				std::string line;
				for (int n = 1; std::getline(in, line); n++)
				{
					std::smatch m;
					if (std::regex_search(line, m, top))
					{
						EXPECT_TRUE(m[1] == "Localiser" && f.path().filename() == "Localiser.cpp")
							<< f.path().string() << ":" << n << ": area '" << area << "' includes the top level's <shadyloc/"
							<< m[1] << ".h>, which is above every area";
					}
					if (!std::regex_search(line, m, inc)) continue;
					const std::string to = m[1];
					// core (settings, errors: library-wide services) is there for every area.
					EXPECT_TRUE(to == area || to == "core" || it->second.count(to))
						<< f.path().string() << ":" << n << ": area '" << area << "' includes '" << to
						<< "', which docs/architecture.md's area graph does not allow";
				}
			}
		}
	EXPECT_GT(files, 50u);	// the walk found the sources
}

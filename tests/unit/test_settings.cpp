/* ShadyLoc tests: settings are read strictly and every options struct's dump
 * loads back to the same values. */
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/vo/StereoVO.h>

#include <gtest/gtest.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <functional>
#include <sstream>
#include <string>

using namespace shadyloc;

namespace
{
/** Runs load, expects it to throw, and the message to contain every part. */
void expectRefused(
	const std::function<void()>& load, const std::vector<std::string>& mustContain, const std::string& what)
{
	try
	{
		load();
		ADD_FAILURE() << what << ": accepted";
	}
	catch (const std::exception& e)
	{
		for (const auto& m : mustContain)
			EXPECT_NE(std::string(e.what()).find(m), std::string::npos)
				<< what << ": message '" << e.what() << "' lacks '" << m << "'";
	}
}
}  // namespace

// Regression: TStereoVOOptions::dumpToTextStream wrote "two_view_ba = true ;
// comment", which MRPT read back as false (its bool reader does not strip the
// comment); ransac_prediction likewise. A dump must load back to the same options.
TEST(Settings, VOOptionsDumpLoadsBackIdentically)
{
	vo::TStereoVOOptions o;
	ASSERT_TRUE(o.two_view_ba);
	ASSERT_TRUE(o.ransac_prediction);
	std::ostringstream dump;
	o.dumpToTextStream(dump);
	mrpt::config::CConfigFileMemory c("[vo]\n" + dump.str());
	vo::TStereoVOOptions back;
	back.loadFromConfigFile(c, "vo");
	EXPECT_TRUE(back.two_view_ba) << dump.str();
	EXPECT_TRUE(back.ransac_prediction) << dump.str();
	EXPECT_TRUE(back.constant_velocity) << dump.str();
	std::ostringstream again;
	back.dumpToTextStream(again);
	EXPECT_EQ(again.str(), dump.str());
}

// Regression (issue 9, fault 5): config values silently became other numbers.
TEST(Settings, FeatureNumbersOutOfRangeOrNotNumbersAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c("[features]\n" + line + "\n");
			features::TStereoFeatureOptions o;
			o.loadFromConfigFile(c, "features");
		};
	};
	for (const char* line :
		 {"fast_threshold = 1e308", "fast_threshold = 12.5", "fast_threshold = abc",
		  "max_per_cell = 2147483648", "max_per_cell = 4294967308", "max_per_cell = -2147483649",
		  "brief_seed = 4294967296", "brief_seed = -1", "sigma_px = nan", "sigma_px = inf",
		  "max_depth = 1e400", "min_zncc = 0.8x", "dense_check = maybe", "dense_check = 2"})
	{
		const std::string l(line);
		expectRefused(load(l), {"[features]", l.substr(0, l.find(' '))}, l);
	}
}

TEST(Settings, VONumbersOutOfRangeOrNotNumbersAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c("[vo]\n" + line + "\n");
			vo::TStereoVOOptions o;
			o.loadFromConfigFile(c, "vo");
		};
	};
	for (const char* line :
		 {"kf_rotation_deg = inf", "max_lost_frames = 4294967299", "ransac_iterations = 1e308",
		  "huber_k = 1.0.0", "two_view_ba = ja", "max_step_rotation_deg = 30 deg"})
	{
		const std::string l(line);
		expectRefused(load(l), {"[vo]", l.substr(0, l.find(' '))}, l);
	}
}

TEST(Settings, FilterNumbersThatAreTextAreRefused)
{
	auto load = [](const std::string& line) {
		return [line] {
			mrpt::config::CConfigFileMemory c(
				"[filters]\npipeline = inv\n[inv]\nclass = CFilterInvariant\n" + line + "\n");
			filters::FilterPipeline::FromConfig(c, "test.ini");
		};
	};
	for (const char* line :
		 {"beta = abc", "alpha = 0.4.8", "scale = 1e999", "offset = nan", "parallel_eyes = yes please"})
	{
		const std::string l(line);
		expectRefused(load(l), {"test.ini", "[inv]", l.substr(0, l.find(' '))}, l);
	}
}

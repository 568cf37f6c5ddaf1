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

/* ShadyLoc tests: channels as filter objects. One .ini section defines a
 * channel for filtering and for the VO; a filtered rawlog and the filter run
 * on the fly give the same frames. */
#include <shadyloc/filters/Channel.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/io/StereoFrameSource.h>
#include <shadyloc/io/Tum.h>
#include <shadyloc/sim/SyntheticCorridor.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <opencv2/core.hpp>

#include "../support/TestSupport.h"

#include <fstream>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** n colour frames of the textured corridor (the VO tracks it). */
void writeCorridor(const std::string& rawlog, int n)
{
	sim::SyntheticCorridor corridor;
	const auto c = corridor.calib();
	io::RawlogWriter w(rawlog);
	for (int k = 0; k < n; k++)
	{
		cv::Mat l, r;
		corridor.render(sim::SyntheticCorridor::examplePose(k), l, r, k);
		w.write(test::stereoObservation(l, r, c, 1000.0 + 0.1 * k));
	}
	w.commit();
}

/** A pipeline of three channels with non-default names and suffixes. */
const char* kCustom =
	"[filters]\npipeline = grey flat lin\n"
	"[grey]\nclass = CFilterMonochrome\noutput_suffix = _grey\nchannel_order = rgb\n"
	"[flat]\nclass = shadyloc::CFilterInvariant\noutput_suffix = _flat\nalpha = 0.40\nbeta = 0.60\n"
	"[lin]\nclass = CFilterLinearise\noutput_suffix = _lin\nlinearisation = gamma\ngamma = 1.8\n";
}  // namespace

TEST(FilterChannels, NamedBySectionOrSuffixBuiltByClass)
{
	// A config's own pipeline: by section name or by suffix.
	mrpt::config::CConfigFileMemory custom(kCustom);
	const auto flat = filters::channelFromConfig(custom, "flat", "custom.ini");
	EXPECT_EQ(flat.label, "flat");
	EXPECT_EQ(flat.suffix(), "_flat");
	const auto* inv = dynamic_cast<const CFilterInvariant*>(flat.filter.get());
	ASSERT_NE(inv, nullptr);
	EXPECT_EQ(inv->params().alpha, 0.40);
	EXPECT_EQ(filters::channelFromConfig(custom, "_lin", "custom.ini").label, "lin");
	EXPECT_TRUE(filters::channelFromConfig(custom, "lin", "custom.ini").isNamed("lin"));

	// config/vo.ini: sections [mono] and [invariant]; "inv" (the suffix) finds
	// [invariant], so [features.invariant] and [vo.invariant] apply to it.
	mrpt::config::CConfigFile vo(std::string(SHADYLOC_SOURCE_DIR) + "/config/vo.ini");
	const auto i1 = filters::channelFromConfig(vo, "inv", "vo.ini");
	EXPECT_EQ(i1.label, "invariant");
	EXPECT_EQ(i1.suffix(), "_inv");
	EXPECT_TRUE(i1.filter->sameImagesAs(*filters::defaultChannel("invariant").filter));	 // the paper's values
	EXPECT_EQ(std::string(filters::channelFromConfig(vo, "mono", "vo.ini").filter->GetRuntimeClass()->className),
			  "shadyloc::CFilterMonochrome");

	// A built-in channel's section may leave the class out; its keys apply.
	mrpt::config::CConfigFileMemory noClass("[invariant]\nalpha = 0.40\nbeta = 0.60\n");
	const auto i2 = filters::channelFromConfig(noClass, "invariant", "old.ini");
	EXPECT_FALSE(i2.filter->sameImagesAs(*i1.filter));
	EXPECT_NE(i2.filter->describe().find("alpha=0.4 beta=0.6"), std::string::npos) << i2.filter->describe();

	// No config: the built-in channels.
	mrpt::config::CConfigFileMemory none("");
	EXPECT_EQ(filters::channelFromConfig(none, "inv", "-").label, "invariant");

	// Errors name the file, the section and key, or the names known.
	auto e = test::errorOf([&] { filters::channelFromConfig(none, "sepia", "x.ini"); });
	EXPECT_NE(e.find("'x.ini': unknown channel 'sepia'"), std::string::npos) << e;
	EXPECT_NE(e.find("mono (_mono), invariant (_inv)"), std::string::npos) << e;
	e = test::errorOf([&] { filters::channelFromConfig(custom, "sepia", "custom.ini"); });
	EXPECT_NE(e.find("the config's pipeline has grey (_grey), flat (_flat), lin (_lin)"), std::string::npos) << e;
	mrpt::config::CConfigFileMemory classless("[sepia]\ntone = 3\n");
	e = test::errorOf([&] { filters::channelFromConfig(classless, "sepia", "s.ini"); });
	EXPECT_NE(e.find("'s.ini': [sepia] class: missing"), std::string::npos) << e;
	mrpt::config::CConfigFileMemory bad("[invariant]\nclass = CFilterInvariant\nalpha = 7\n");
	e = test::errorOf([&] { filters::channelFromConfig(bad, "invariant", "bad.ini"); });
	EXPECT_NE(e.find("'bad.ini'"), std::string::npos) << e;
	EXPECT_NE(e.find("[invariant]"), std::string::npos) << e;
	EXPECT_NE(e.find("alpha"), std::string::npos) << e;
}

TEST(FilterChannels, FilteredRawlogAndOnTheFlyGiveTheSameFrames)
{
	const std::string dir = test::tempDir("filter_channels_same");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog";
	test::writeSyntheticRawlog(raw, 4, true);
	mrpt::config::CConfigFileMemory cfg(kCustom);
	filters::RawlogFilterProcessor proc;
	proc.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	proc.run(raw, filt, filters::FilterPipeline::FromConfig(cfg, "custom.ini"));
	// The record names the filters by their sections: the channel names.
	const std::string rec = filters::readPipelineRecord(filt);
	EXPECT_NE(rec.find("[flat]"), std::string::npos) << rec;

	for (const std::string name : {"grey", "flat", "lin"})
	{
		const auto ch = filters::channelFromConfig(cfg, name, "custom.ini");
		const auto a = filters::resolveChannelInput(filt, ch);
		EXPECT_TRUE(a.filtered);
		EXPECT_EQ(a.sensorLabel, "CAMERA" + ch.suffix());
		ASSERT_TRUE(a.recorded);
		EXPECT_TRUE(a.recorded->sameImagesAs(*ch.filter));
		const auto b = filters::resolveChannelInput(raw, ch);
		EXPECT_FALSE(b.filtered);
		EXPECT_FALSE(b.hasRecord);
		// On the filtered rawlog, not filtered: the source camera, not a derived channel.
		const auto c = filters::resolveChannelInput(filt, filters::defaultChannel("mono"));
		EXPECT_FALSE(c.filtered);

		// The one frame source: the channel read from the filtered rawlog,
		// made on the fly from the unfiltered one; the same images.
		filters::ChannelFrameSource sa(filt, {ch}), sb(raw, {ch});
		EXPECT_TRUE(sa.input(0).filtered);
		EXPECT_FALSE(sb.input(0).filtered);
		filters::TChannelFrame fa, fb;
		int n = 0;
		while (sa.next(fa))
		{
			ASSERT_TRUE(sb.next(fb));
			EXPECT_EQ(fa.camera, "CAMERA");
			EXPECT_EQ(fb.camera, "CAMERA");
			EXPECT_TRUE(fa.channels[0].read);
			EXPECT_FALSE(fb.channels[0].read);
			EXPECT_TRUE(fa.left.empty());  // the colour pair is not read when not needed
			EXPECT_EQ(fa.channels[0].left.type(), name == "lin" ? CV_8UC3 : CV_8UC1);	 // linearised colour
			EXPECT_EQ(cv::norm(fa.channels[0].left, fb.channels[0].left, cv::NORM_INF), 0) << name << " frame " << n;
			EXPECT_EQ(cv::norm(fa.channels[0].right, fb.channels[0].right, cv::NORM_INF), 0) << name << " frame " << n;
			EXPECT_EQ(fa.timestamp, fb.timestamp);
			EXPECT_EQ(fa.calib.baseline, fb.calib.baseline);
			n++;
		}
		EXPECT_EQ(n, 4) << name;
		EXPECT_FALSE(sb.next(fb));
	}
}

TEST(FilterChannels, VoAppRunsOneSectionsChannelFilteredOrNot)
{
	// `shadyloc vo --channel NAME -c cfg` with cfg defining the channel: the
	// filtered rawlog's images and the filter on the fly give the same poses.
	const std::string dir = test::tempDir("filter_channels_vo");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog", ini = dir + "/c.ini";
	writeCorridor(raw, 8);
	std::ofstream(ini) << kCustom;
	std::string out;
	ASSERT_EQ(test::runCommand(test::appPath() + " filter -q -i " + raw + " -o " + filt + " -c " + ini, &out), 0)
		<< out;
	for (const std::string name : {"flat", "grey"})
	{
		const std::string ta = dir + "/" + name + "_f.tum", tb = dir + "/" + name + "_raw.tum";
		ASSERT_EQ(
			test::runCommand(
				test::appPath() + " vo -i " + filt + " --channel " + name + " -c " + ini + " -o " + ta, &out),
			0)
			<< out;
		EXPECT_NE(out.find("input: filtered observations 'CAMERA_" + name + "'"), std::string::npos) << out;
		EXPECT_NE(out.find(name + " images made with the config's parameters"), std::string::npos) << out;
		ASSERT_EQ(
			test::runCommand(
				test::appPath() + " vo -i " + raw + " --channel " + name + " -c " + ini + " -o " + tb, &out),
			0)
			<< out;
		EXPECT_NE(out.find("converted on the fly"), std::string::npos) << out;
		// The corridor is tracked: the poses are the VO's, not a lost run's identities.
		const auto est = io::readTum(ta);
		ASSERT_EQ(est.size(), 8u);
		EXPECT_GT(est.back().T.translation().norm(), 0.3) << name;	// 0.7 m travelled
		EXPECT_NE(out.find("frames: 8, tracked: 8"), std::string::npos) << out;
		EXPECT_EQ(test::fileContents(ta), test::fileContents(tb)) << name << ": filtered and on-the-fly runs differ";
	}
	// A channel of colour images cannot drive the VO: said, naming it.
	EXPECT_NE(
		test::runCommand(
			test::appPath() + " vo -i " + raw + " --channel lin -c " + ini + " -o " + dir + "/lin.tum", &out),
		0);
	EXPECT_NE(out.find("channel 'lin' gives 3-channel images; the VO needs a grey channel"), std::string::npos)
		<< out;
	EXPECT_FALSE(fs::exists(dir + "/lin.tum"));
	// The retired [vo] channel_order key says where it went.
	std::ofstream(dir + "/old.ini") << "[vo]\nchannel_order = bgr\n";
	EXPECT_NE(
		test::runCommand(test::appPath() + " vo -i " + raw + " -c " + dir + "/old.ini -o " + dir + "/x.tum", &out), 0);
	EXPECT_NE(out.find("[vo] channel_order: moved to the channel's filter section"), std::string::npos) << out;
	EXPECT_FALSE(fs::exists(dir + "/x.tum"));
}

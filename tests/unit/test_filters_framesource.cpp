/* ShadyLoc tests: the channels' one frame source (filters/ChannelFrameSource.h).
 * Channels read from a filtered rawlog, made from colour, or both at once
 * give the same frames; making can be deferred; channels whose observations
 * do not pair up, differ in calibration, or cannot be made (no colour) are
 * errors naming the file and the frame. */
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/filters/FilterPipeline.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <opencv2/core.hpp>

#include "../support/TestSupport.h"

using namespace shadyloc;

namespace
{
std::vector<filters::TChannel> defaultChannels()
{
	return {filters::defaultChannel("mono"), filters::defaultChannel("invariant")};
}

/** A raw rawlog of n frames and its filtered copy (default pipeline, or only `pipeline`). */
void writeRawAndFiltered(const std::string& raw, const std::string& filt, int n, const std::string& pipeline = "")
{
	test::writeSyntheticRawlog(raw, n, true);
	filters::RawlogFilterProcessor proc;
	proc.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	mrpt::config::CConfigFileMemory cfg(pipeline);
	proc.run(raw, filt, pipeline.empty() ? filters::FilterPipeline::Default() : filters::FilterPipeline::FromConfig(cfg, "test"));
}

/** The stereo observations of a rawlog, rewritten by `edit` (return null to drop one). */
void rewrite(
	const std::string& in, const std::string& out,
	const std::function<mrpt::obs::CObservationStereoImages::Ptr(const mrpt::obs::CObservationStereoImages::Ptr&, size_t)>& edit)
{
	io::RawlogWriter w(out);
	io::RawlogReader r(in);
	size_t k = 0;
	while (const auto obj = r.next())
		for (const auto& o : io::observationsIn(obj))
		{
			const auto st = std::dynamic_pointer_cast<mrpt::obs::CObservationStereoImages>(o);
			if (!st)
				w.write(*o);  // the filter record
			else if (const auto e = edit(st, k++))
				w.write(*e);
		}
	w.commit();
}

std::string errorOfNext(filters::ChannelFrameSource& src)
{
	try
	{
		filters::TChannelFrame f;
		while (src.next(f))
		{
		}
	}
	catch (const io::RawlogError& e)
	{
		return e.what();
	}
	return "";
}

bool same(const cv::Mat& a, const cv::Mat& b) { return a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0; }
}  // namespace

TEST(FilterFrameSource, ReadMadeAndMixedChannelsGiveTheSameFrames)
{
	const std::string dir = test::tempDir("frame_source_same");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog", part = dir + "/part.rawlog";
	writeRawAndFiltered(raw, filt, 4);
	// Only the monochrome channel filtered: the invariant one made from colour.
	writeRawAndFiltered(dir + "/raw2.rawlog", part, 4, "[filters]\npipeline = mono\n[mono]\nclass = CFilterMonochrome\noutput_suffix = _mono\n");
	filters::ChannelFrameSource made(raw, defaultChannels()), read(filt, defaultChannels()), mixed(part, defaultChannels());
	EXPECT_FALSE(made.input(0).filtered);
	EXPECT_TRUE(read.input(0).filtered && read.input(1).filtered);
	EXPECT_TRUE(mixed.input(0).filtered);
	EXPECT_FALSE(mixed.input(1).filtered);
	filters::TChannelFrame a, b, c;
	size_t n = 0;
	while (made.next(a))
	{
		ASSERT_TRUE(read.next(b));
		ASSERT_TRUE(mixed.next(c));
		EXPECT_EQ(a.index, n);
		EXPECT_EQ(b.timestamp, a.timestamp);
		EXPECT_EQ(c.timestamp, a.timestamp);
		EXPECT_EQ(b.calib.fx, a.calib.fx);
		EXPECT_EQ(b.camera, "CAMERA");
		EXPECT_FALSE(a.left.empty());
		EXPECT_TRUE(b.left.empty());  // every channel read: the colour pair is not needed
		for (size_t i = 0; i < 2; i++)
		{
			EXPECT_EQ(a.channels[i].left.type(), CV_8UC1);
			EXPECT_TRUE(same(a.channels[i].left, b.channels[i].left)) << "frame " << n << " channel " << i;
			EXPECT_TRUE(same(a.channels[i].right, b.channels[i].right)) << "frame " << n << " channel " << i;
			EXPECT_TRUE(same(a.channels[i].left, c.channels[i].left)) << "frame " << n << " channel " << i;
		}
		EXPECT_TRUE(c.channels[0].read);
		EXPECT_FALSE(c.channels[1].read);
		n++;
	}
	EXPECT_EQ(n, 4u);
	EXPECT_FALSE(read.next(b));
	EXPECT_FALSE(mixed.next(c));
}

TEST(FilterFrameSource, DeferredMakingGivesTheSameImages)
{
	const std::string dir = test::tempDir("frame_source_deferred");
	const std::string raw = dir + "/raw.rawlog";
	test::writeSyntheticRawlog(raw, 2, false);
	filters::TChannelFrameSourceOptions o;
	o.makeChannels = false;
	filters::ChannelFrameSource lazy(raw, defaultChannels(), o), eager(raw, defaultChannels());
	filters::TChannelFrame a, b;
	while (lazy.next(a))
	{
		ASSERT_TRUE(eager.next(b));
		EXPECT_TRUE(a.channels[1].left.empty());
		lazy.make(a, 1);
		EXPECT_TRUE(same(a.channels[1].left, b.channels[1].left));
		EXPECT_TRUE(same(a.channels[1].right, b.channels[1].right));
	}
	// No channels: the colour frames themselves.
	filters::ChannelFrameSource colour(raw, {});
	ASSERT_TRUE(colour.next(a));
	EXPECT_EQ(a.left.type(), CV_8UC3);
	EXPECT_TRUE(a.channels.empty());
}

TEST(FilterFrameSource, UnpairedChannelsNameTheFileAndFrame)
{
	const std::string dir = test::tempDir("frame_source_unpaired");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog";
	writeRawAndFiltered(raw, filt, 4);
	// Frame 2's invariant pair missing (a partly filtered or damaged rawlog).
	const std::string gap = dir + "/gap.rawlog";
	rewrite(filt, gap, [](const auto& o, size_t) {
		return o->sensorLabel == "CAMERA_inv" && o->timestamp == test::syntheticStereoFrame(2)->timestamp ? nullptr : o;
	});
	filters::ChannelFrameSource g(gap, defaultChannels());
	std::string e = errorOfNext(g);
	EXPECT_NE(e.find("gap.rawlog"), std::string::npos) << e;
	EXPECT_NE(e.find("frame 2"), std::string::npos) << e;
	EXPECT_NE(e.find("'CAMERA_inv'"), std::string::npos) << e;
	EXPECT_NE(e.find("pair up"), std::string::npos) << e;
	// The last frame's invariant pair missing: the end of the rawlog says so.
	const std::string end = dir + "/end.rawlog";
	rewrite(filt, end, [](const auto& o, size_t) {
		return o->sensorLabel == "CAMERA_inv" && o->timestamp == test::syntheticStereoFrame(3)->timestamp ? nullptr : o;
	});
	filters::ChannelFrameSource t(end, defaultChannels());
	e = errorOfNext(t);
	EXPECT_NE(e.find("end.rawlog': frame 3"), std::string::npos) << e;
	EXPECT_NE(e.find("but no 'CAMERA_inv'"), std::string::npos) << e;
	// A derived pair whose calibration is not its frame's.
	const std::string cal = dir + "/calib.rawlog";
	rewrite(filt, cal, [](const auto& o, size_t) {
		if (o->sensorLabel != "CAMERA_mono") return o;
		auto c = mrpt::obs::CObservationStereoImages::Create(*o);
		c->leftCamera.fx(c->leftCamera.fx() + 1);	 // still rectified: both eyes
		c->rightCamera.fx(c->rightCamera.fx() + 1);
		return c;
	});
	filters::ChannelFrameSource c(cal, defaultChannels());
	e = errorOfNext(c);
	EXPECT_NE(e.find("calib.rawlog"), std::string::npos) << e;
	// (Every channel read: the colour pair is not looked at; the invariant
	// pair is checked against the monochrome one.)
	EXPECT_NE(e.find("frame 0 (sensor 'CAMERA_inv')"), std::string::npos) << e;
	EXPECT_NE(e.find("calibration differs from 'CAMERA_mono''s of the same frame"), std::string::npos) << e;
}

TEST(FilterFrameSource, ChannelsWithoutColourOrDerivedImagesAreRefused)
{
	const std::string dir = test::tempDir("frame_source_nocolour");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog", grey = dir + "/grey.rawlog";
	writeRawAndFiltered(raw, filt, 3);
	// The derived channels alone (the colour pairs dropped): still read.
	rewrite(filt, grey, [](const auto& o, size_t) { return o->sensorLabel == "CAMERA" ? nullptr : o; });
	filters::ChannelFrameSource ok(grey, defaultChannels());
	filters::TChannelFrame f;
	ASSERT_TRUE(ok.next(f));
	EXPECT_EQ(f.camera, "CAMERA");
	EXPECT_EQ(f.channels[1].left.type(), CV_8UC1);
	// A channel it does not hold cannot be made without colour.
	mrpt::config::CConfigFileMemory cfg("[lin]\nclass = CFilterLinearise\noutput_suffix = _lin\n");
	const auto lin = filters::channelFromConfig(cfg, "lin", "test.ini");
	try
	{
		filters::ChannelFrameSource bad(grey, {filters::defaultChannel("mono"), lin});
		FAIL() << "a channel without colour to make it from was accepted";
	}
	catch (const io::RawlogError& e)
	{
		const std::string m = e.what();
		EXPECT_NE(m.find("grey.rawlog"), std::string::npos) << m;
		EXPECT_NE(m.find("no colour stereo observations"), std::string::npos) << m;
		EXPECT_NE(m.find("'lin'"), std::string::npos) << m;
	}
}

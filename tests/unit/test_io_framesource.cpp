/* ShadyLoc tests: the stereo frame source, and each rawlog reader resolving
 * its own external images. */
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/io/StereoFrameSource.h>

#include <mrpt/img/CImage.h>

#include <opencv2/core.hpp>

#include "../support/TestSupport.h"

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
/** Frame i of rawlog "A" (the synthetic frame) or "B" (its negative). */
cv::Mat expected(bool negative, int i, bool left)
{
	const auto o = test::syntheticStereoFrame(i);
	cv::Mat m = (left ? o->imageLeft : o->imageRight).asCvMatRef().clone();
	if (negative) m = cv::Scalar::all(255) - m;
	return m;
}

/** n frames with external images named CAMERA_<i>_{left,right}.png: the same
 * names in every rawlog written this way, so a reader looking in the wrong
 * folder finds a file, only with the wrong pixels. */
void writeExternal(const std::string& path, int n, bool negative)
{
	io::RawlogWriter w(path, true);
	for (int i = 0; i < n; i++)
	{
		auto o = test::syntheticStereoFrame(i);
		for (bool left : {true, false})
		{
			auto& img = left ? o->imageLeft : o->imageRight;
			img = mrpt::img::CImage(expected(negative, i, left), mrpt::img::DEEP_COPY);
			w.externalise(img, "CAMERA_" + std::to_string(i) + (left ? "_left.png" : "_right.png"));
		}
		w.write(*o);
	}
	w.commit();
}
}  // namespace

TEST(IoExternalImages, TwoReadersOpenAtOnceEachReadTheirOwnImages)
{
	const std::string dir = test::tempDir("io_two_readers");
	fs::create_directories(dir + "/survey");
	fs::create_directories(dir + "/live");
	const std::string a = dir + "/survey/run.rawlog", b = dir + "/live/run.rawlog";
	writeExternal(a, 3, false);
	writeExternal(b, 3, true);
	ASSERT_TRUE(fs::exists(dir + "/survey/run_Images/CAMERA_0_left.png"));
	ASSERT_TRUE(fs::exists(dir + "/live/run_Images/CAMERA_0_left.png"));

	const std::string globalBase = mrpt::img::CImage::getImagesPathBase();
	// Both open before either reads: the second must not redirect the first.
	io::StereoFrameSource sa(a), sb(b);
	io::TStereoFrame fa, fb;
	for (int i = 0; i < 3; i++)
	{
		ASSERT_TRUE(sa.next(fa));
		ASSERT_TRUE(sb.next(fb));
		EXPECT_TRUE(test::samePixels(fa.left, expected(false, i, true))) << "survey frame " << i;
		EXPECT_TRUE(test::samePixels(fa.right, expected(false, i, false))) << "survey frame " << i;
		EXPECT_TRUE(test::samePixels(fb.left, expected(true, i, true))) << "live frame " << i;
		EXPECT_TRUE(test::samePixels(fb.right, expected(true, i, false))) << "live frame " << i;
		// Each observation now names its file absolutely, in its own folder.
		const fs::path want = fs::absolute(dir) / "survey" / "run_Images" / ("CAMERA_" + std::to_string(i) + "_left.png");
		EXPECT_EQ(fa.obs->imageLeft.getExternalStorageFile(), want.lexically_normal().string());
	}
	EXPECT_FALSE(sa.next(fa));
	EXPECT_FALSE(sb.next(fb));
	EXPECT_EQ(mrpt::img::CImage::getImagesPathBase(), globalBase) << "a reader changed the process-wide images path";
}

TEST(IoStereoFrameSource, BothRawlogStylesGiveTheSameFrames)
{
	const std::string dir = test::tempDir("io_frames_styles");
	for (const bool sf : {false, true})
	{
		const std::string path = dir + (sf ? "/sf.rawlog" : "/obs.rawlog");
		test::writeSyntheticRawlog(path, 4, sf);
		io::StereoFrameSource src(path);
		io::TStereoFrame f;
		int n = 0;
		while (src.next(f))
		{
			const auto o = test::syntheticStereoFrame(n);
			EXPECT_EQ(f.index, size_t(n));
			// Sensory-frame style: action, frame, action, frame, ...
			EXPECT_EQ(f.object, sf ? size_t(2 * n + 1) : size_t(n));
			EXPECT_EQ(f.sensorLabel, "CAMERA");
			EXPECT_DOUBLE_EQ(f.timestamp, mrpt::Clock::toDouble(o->timestamp));
			EXPECT_TRUE(test::samePixels(f.left, o->imageLeft.asCvMatRef()));
			EXPECT_TRUE(test::samePixels(f.right, o->imageRight.asCvMatRef()));
			EXPECT_EQ(f.calib.fx, 200.0);
			EXPECT_EQ(f.calib.cx, 80.0);
			EXPECT_NEAR(f.calib.baseline, 0.12, 1e-12);
			EXPECT_EQ(f.camera.leftCamera.ncols, 160u);
			n++;
		}
		EXPECT_EQ(n, 4) << path;
		EXPECT_EQ(src.frames(), 4u);
	}
}

TEST(IoStereoFrameSource, CalibrationChangeNamesFileObjectAndFrame)
{
	const std::string dir = test::tempDir("io_frames_calib");
	const std::string path = dir + "/c.rawlog";
	{
		io::RawlogWriter w(path);
		for (int i = 0; i < 4; i++)
		{
			auto o = test::syntheticStereoFrame(i);
			if (i == 2) o->leftCamera.setIntrinsicParamsFromValues(210, 200, 80, 60);
			w.write(*o);
		}
		w.commit();
	}
	io::StereoFrameSource src(path);
	io::TStereoFrame f;
	ASSERT_TRUE(src.next(f));
	ASSERT_TRUE(src.next(f));
	try
	{
		src.next(f);
		FAIL() << "a changed calibration was accepted";
	}
	catch (const io::RawlogError& e)
	{
		const std::string m = e.what();
		EXPECT_NE(m.find("'" + path + "': object #2: frame 2"), std::string::npos) << m;
		EXPECT_NE(m.find("calibration differs from frame 0: left intrinsics fx=210"), std::string::npos) << m;
	}
}

// survey, localise (and vo) read frames here: a repeated or earlier frame
// time is refused where it enters, naming the frame and both times.
TEST(IoStereoFrameSource, RepeatedOrEarlierTimestampNamesTheFrame)
{
	const std::string dir = test::tempDir("io_frames_time");
	for (const int earlier : {1, 0})  // frame 1's time again; frame 0's
	{
		const std::string path = dir + "/t.rawlog";
		{
			io::RawlogWriter w(path);
			for (int i = 0; i < 4; i++)
			{
				auto o = test::syntheticStereoFrame(i);
				if (i == 2) o->timestamp = test::syntheticStereoFrame(earlier)->timestamp;
				w.write(*o);
			}
			w.commit();
		}
		io::StereoFrameSource src(path);
		io::TStereoFrame f;
		ASSERT_TRUE(src.next(f));
		ASSERT_TRUE(src.next(f));
		try
		{
			src.next(f);
			ADD_FAILURE() << "frame 2 at frame " << earlier << "'s time was accepted";
		}
		catch (const io::RawlogError& e)
		{
			const std::string m = e.what();
			EXPECT_NE(m.find("'" + path + "': object #2: frame 2"), std::string::npos) << m;
			EXPECT_NE(m.find("is not after frame 1's ("), std::string::npos) << m;
		}
		// The program says the same and writes no map.
		std::string out;
		EXPECT_NE(test::runCommand(test::appPath() + " survey -q -i " + path + " -o " + dir + "/m.kfmap", &out), 0) << out;
		EXPECT_NE(out.find("frame 2"), std::string::npos) << out;
		EXPECT_FALSE(fs::exists(dir + "/m.kfmap"));
	}
}

TEST(IoStereoFrameSource, PicksChannelsByLabelSuffix)
{
	const std::string dir = test::tempDir("io_frames_labels");
	const std::string raw = dir + "/raw.rawlog", filt = dir + "/filt.rawlog";
	test::writeSyntheticRawlog(raw, 3, true);
	filters::RawlogFilterProcessor proc;
	proc.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	proc.run(raw, filt, filters::FilterPipeline::Default());

	// By suffix: the derived channel; grey images, same calibration and stamps.
	io::TStereoFrameSourceOptions o;
	o.acceptLabel = io::labelWithSuffix("_inv");
	io::StereoFrameSource inv(filt, o);
	io::TStereoFrame f;
	ASSERT_TRUE(inv.next(f));
	EXPECT_EQ(inv.sensorLabel(), "CAMERA_inv");
	EXPECT_EQ(f.left.type(), CV_8UC1);
	EXPECT_EQ(f.calib.fx, 200.0);
	// The source camera of a filtered rawlog: not one of its derived channels,
	// its images as stored.
	o.acceptLabel = io::labelWithoutSuffixes({"_mono", "_inv"});
	io::StereoFrameSource cam(filt, o);
	int n = 0;
	while (cam.next(f))
	{
		EXPECT_EQ(f.sensorLabel, "CAMERA");
		EXPECT_TRUE(test::samePixels(f.left, test::syntheticStereoFrame(n)->imageLeft.asCvMatRef()));
		EXPECT_TRUE(test::samePixels(f.right, test::syntheticStereoFrame(n)->imageRight.asCvMatRef()));
		n++;
	}
	EXPECT_EQ(n, 3);
	EXPECT_EQ(io::findStereoLabel(filt, io::labelWithSuffix("_mono", "CAMERA")), "CAMERA_mono");
	EXPECT_EQ(io::findStereoLabel(filt, io::labelWithSuffix("_mono", "OTHER")), "");

	// A label that is not there: no frames, and the message lists the labels.
	io::TStereoFrameSourceOptions none;
	none.sensorLabel = "STEREO";
	io::StereoFrameSource missing(filt, none);
	EXPECT_FALSE(missing.next(f));
	const std::string m = missing.noFramesMessage();
	EXPECT_NE(m.find("no stereo observations labelled 'STEREO'"), std::string::npos) << m;
	EXPECT_NE(m.find("'CAMERA_inv'"), std::string::npos) << m;
}

/* ShadyLoc — a localisation run's frame as a picture (LocalisedFrame.h). */
#include "LocalisedFrame.h"

#include "LocalisedView.h"

#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/render/AnimatedGif.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace shadyloc::apps
{
using localisation::TLocalisationUpdate;
using localisation::TLocaliserResult;

namespace
{
// Exact entries of the GIF palette (render/AnimatedGif.h), BGR: drawn
// without anti-aliasing, they stay the same colour frame after frame.
const cv::Scalar kInlierColour(0, 204, 0), kOutlierColour(0, 0, 255), kWhite(255, 255, 255);
constexpr double kTextScale = 0.4;
constexpr int kCaptionHeight = 15;	// px: one line of text at kTextScale

cv::Scalar toBgr(const mrpt::img::TColor& c) { return {double(c.B), double(c.G), double(c.R)}; }

/** A dark band across the top of `img` with `text` in `colour`, made
 * smaller if it would not fit. */
void drawCaption(cv::Mat& img, const std::string& text, const cv::Scalar& colour)
{
	cv::rectangle(img, cv::Rect(0, 0, img.cols, kCaptionHeight), cv::Scalar(0, 0, 0), cv::FILLED);
	const int width = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, kTextScale, 1, nullptr).width;
	const double scale = kTextScale * std::min(1.0, (img.cols - 8.0) / std::max(width, 1));
	cv::putText(img, text, {4, kCaptionHeight - 4}, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

/** Text at (x, baseline y) in `colour`; returns the x after it. */
int drawText(cv::Mat& img, const std::string& text, int x, int y, const cv::Scalar& colour)
{
	cv::putText(img, text, {x, y}, cv::FONT_HERSHEY_SIMPLEX, kTextScale, colour, 1, cv::LINE_AA);
	int base = 0;
	return x + cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, kTextScale, 1, &base).width;
}

/** The localiser's matches on its channel's image scaled by s: outliers as
 * red crosses, inliers as green dots over them. */
void drawMatches(cv::Mat& panel, const TLocaliserResult& r, double s)
{
	for (const bool inliers : {false, true})
		for (const auto& m : r.live_matches)
		{
			if (m.inlier != inliers) continue;
			const cv::Point p(int(std::lround(m.u * s)), int(std::lround(m.v * s)));
			if (m.inlier)
				cv::circle(panel, p, 2, kInlierColour, cv::FILLED, cv::LINE_8);
			else
				cv::drawMarker(panel, p, kOutlierColour, cv::MARKER_TILTED_CROSS, 5, 1, cv::LINE_8);
		}
}

/** One channel's panel: its image, its localiser's matches, a caption, and
 * a frame in the localiser's colour when its fix is the one used. */
cv::Mat channelPanel(const TChannelImage& im, const TLocaliserResult& r, const TLocalisationUpdate& u, cv::Size size)
{
	const bool used = u.used == r.channel;
	if (im.left.type() != CV_8UC1) throw std::runtime_error("channel " + im.channel + ": the live image is not 8-bit grey");
	cv::Mat grey, panel;
	cv::resize(im.left, grey, size, 0, 0, cv::INTER_AREA);
	cv::cvtColor(grey, panel, cv::COLOR_GRAY2BGR);
	drawMatches(panel, r, double(size.width) / im.left.cols);
	int inliers = 0;
	for (const auto& m : r.live_matches) inliers += m.inlier;
	std::ostringstream text;
	text << r.channel << " " << inliers << "/" << r.live_matches.size() << " inliers: "
		 << (used ? "fix used" : localisation::toString(r.status));
	if (u.global_search && r.live_matches.empty()) text.str(r.channel + ": searching the map");
	const cv::Scalar colour = toBgr(colourOfUsed(r.channel));
	drawCaption(panel, text.str(), used ? colour : kWhite);
	if (used) cv::rectangle(panel, cv::Rect({0, 0}, size), colour, 2);
	return panel;
}

/** The map and the live path so far, top-down, captioned with the frame and
 * the colour key of who held the place. */
cv::Mat topDownPanel(const CKeyframeMap& map, const std::vector<TLocalisationUpdate>& ups, cv::Size size)
{
	render::SnapshotOptions o;
	o.width = unsigned(size.width);
	o.height = unsigned(size.height);
	o.legend = false;
	o.marginFraction = 0.05;
	const mrpt::img::CImage img = render::renderTrajectoriesImage(localisedViewLayers(map, ups), o, {}, "the top-down view");
	cv::Mat view = img.asCvMat<cv::Mat>(mrpt::img::DEEP_COPY);
	if (view.channels() == 1) cv::cvtColor(view, view, cv::COLOR_GRAY2BGR);
	const auto& u = ups.back();
	std::ostringstream head;
	head << "frame " << u.frame << ", " << std::fixed << std::setprecision(1) << u.distance_m << " m: ";
	drawCaption(view, head.str(), kWhite);
	int x = 4 + cv::getTextSize(head.str(), cv::FONT_HERSHEY_SIMPLEX, kTextScale, 1, nullptr).width;
	x = drawText(view, u.localised() ? u.used + " fix" : std::string("no fix"), x, kCaptionHeight - 4, toBgr(colourOfUsed(u.used)));
	x = drawText(view, "   path: ", x, kCaptionHeight - 4, kWhite);
	x = drawText(view, "mono ", x, kCaptionHeight - 4, toBgr(kMonoColour));
	x = drawText(view, "invariant ", x, kCaptionHeight - 4, toBgr(kInvariantColour));
	if (u.result("joint")) x = drawText(view, "joint ", x, kCaptionHeight - 4, toBgr(kJointColour));
	drawText(view, "VO only", x, kCaptionHeight - 4, toBgr(kNoneColour));
	return view;
}

const TChannelImage& imageOf(const std::vector<TChannelImage>& images, const std::string& channel)
{
	for (const auto& im : images)
		if (im.channel == channel) return im;
	throw std::runtime_error("channel " + channel + ": no live image to draw");
}
}  // namespace

cv::Size localisedFrameSize(int width, size_t channels, cv::Size camera)
{
	const int panelWidth = width / int(std::max<size_t>(channels, 1));
	const int panelHeight = int(std::lround(double(panelWidth) * camera.height / camera.width));
	return {width, panelHeight + int(std::lround(width / 3.0))};
}

cv::Mat composeLocalisedFrame(
	const CKeyframeMap& map, const std::vector<TLocalisationUpdate>& ups, const std::vector<TChannelImage>& images,
	int width)
{
	if (ups.empty() || images.empty()) throw std::invalid_argument("composeLocalisedFrame: no frame to draw");
	const auto& u = ups.back();
	// A panel per localiser with live images of its own (not the joint one).
	std::vector<const localisation::TLocaliserResult*> drawn;
	for (const auto& r : u.localisers)
		if (std::any_of(images.begin(), images.end(), [&](const TChannelImage& im) { return im.channel == r.channel; }))
			drawn.push_back(&r);
	const size_t n = drawn.size();
	const cv::Size camera = images.front().left.size();
	const cv::Size size = localisedFrameSize(width, n, camera);
	const cv::Size panel(width / int(std::max<size_t>(n, 1)), size.height - int(std::lround(width / 3.0)));
	cv::Mat frame(size, CV_8UC3, kWhite);
	for (size_t i = 0; i < n; i++)
		channelPanel(imageOf(images, drawn[i]->channel), *drawn[i], u, panel)
			.copyTo(frame(cv::Rect(int(i) * panel.width, 0, panel.width, panel.height)));
	const cv::Rect below(0, panel.height, width, size.height - panel.height);
	topDownPanel(map, ups, below.size()).copyTo(frame(below));
	return frame;
}

LocalisedFrameRecorder::LocalisedFrameRecorder(localisation::LocalisationSystem& sys, const TFrameRecording& o)
	: m_sys(&sys), m_opts(o)
{
	// The channels' images live as long as the frame's measurements: keep a
	// reference to those of a frame to be pictured.
	sys.setFrameHook([this, labels = sys.channelLabels()](
						 TLocalisationUpdate& u, const std::vector<features::TStereoFrame>& meas,
						 const geometry::TStereoCalib&) {
		if (!due(u.frame)) return;
		m_images.clear();
		for (size_t i = 0; i < meas.size() && i < labels.size(); i++) m_images.push_back({labels[i], meas[i].left});
	});
}

LocalisedFrameRecorder::~LocalisedFrameRecorder() { m_sys->setFrameHook({}); }

bool LocalisedFrameRecorder::due(size_t frame) const
{
	return (!m_opts.gifPath.empty() && frame % size_t(m_opts.gifEvery) == 0) ||
		   (m_opts.viewEvery > 0 && frame % size_t(m_opts.viewEvery) == 0);
}

void LocalisedFrameRecorder::onFrame(const CKeyframeMap& map, const std::vector<TLocalisationUpdate>& ups)
{
	const size_t frame = ups.back().frame;
	if (!due(frame)) return;
	const cv::Mat picture = composeLocalisedFrame(map, ups, m_images, m_opts.width);
	if (!m_opts.gifPath.empty() && frame % size_t(m_opts.gifEvery) == 0)
	{
		if (!m_gif)
			m_gif = std::make_unique<render::AnimatedGifWriter>(
				m_opts.gifPath, picture.cols, picture.rows, int(std::lround(100.0 / m_opts.gifFps)));
		m_gif->addFrame(picture);
	}
	if (m_opts.viewEvery > 0 && frame % size_t(m_opts.viewEvery) == 0)
	{
		const std::string path = m_opts.viewDir + "/" + viewFileName(frame);
		io::writeAtomically(path, [&](const std::string& tmp) {
			if (!cv::imwrite(tmp, picture)) throw std::runtime_error("'" + path + "': cannot write PNG");
		});
	}
}

void LocalisedFrameRecorder::finish()
{
	if (m_gif) m_gif->close();
}

size_t LocalisedFrameRecorder::gifFrames() const { return m_gif ? m_gif->frameCount() : 0; }

}  // namespace shadyloc::apps

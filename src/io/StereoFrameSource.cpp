/* ShadyLoc — the stereo frames of a rawlog. */
#include <shadyloc/io/StereoFrameSource.h>

#include <mrpt/core/Clock.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace shadyloc::io
{
namespace
{
bool endsWith(const std::string& s, const std::string& suf)
{
	return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}
}  // namespace

std::string calibrationDifference(const mrpt::img::TStereoCamera& a, const mrpt::img::TStereoCamera& b)
{
	auto cam = [](const mrpt::img::TCamera& x, const mrpt::img::TCamera& y, const char* eye) -> std::string {
		std::ostringstream s;
		s.precision(12);
		if (x.ncols != y.ncols || x.nrows != y.nrows)
			s << eye << " image size " << y.ncols << "x" << y.nrows << " (was " << x.ncols << "x" << x.nrows
			  << ")";
		else if (x.intrinsicParams != y.intrinsicParams)
			s << eye << " intrinsics fx=" << y.fx() << " fy=" << y.fy() << " cx=" << y.cx() << " cy=" << y.cy()
			  << " (was fx=" << x.fx() << " fy=" << x.fy() << " cx=" << x.cx() << " cy=" << x.cy() << ")";
		else if (x.dist != y.dist)
			s << eye << " distortion";
		return s.str();
	};
	if (auto d = cam(a.leftCamera, b.leftCamera, "left"); !d.empty()) return d;
	if (auto d = cam(a.rightCamera, b.rightCamera, "right"); !d.empty()) return d;
	const auto& p = a.rightCameraPose;
	const auto& q = b.rightCameraPose;
	for (int i = 0; i < 7; i++)
		if (p[i] != q[i])
		{
			std::ostringstream s;
			s.precision(12);
			s << "right camera pose " << q.asString() << " (was " << p.asString() << ")";
			return s.str();
		}
	return "";
}

std::function<bool(const std::string&)> labelWithSuffix(const std::string& suffix, const std::string& base)
{
	return [suffix, base](const std::string& l) {
		return endsWith(l, suffix) && (base.empty() || l == base + suffix);
	};
}

std::function<bool(const std::string&)> labelWithoutSuffixes(const std::vector<std::string>& suffixes)
{
	return [suffixes](const std::string& l) {
		for (const auto& s : suffixes)
			if (!s.empty() && endsWith(l, s)) return false;
		return true;
	};
}

std::string findStereoLabel(
	const std::string& rawlogPath, const std::function<bool(const std::string&)>& accept, size_t maxObjects)
{
	RawlogReader rd(rawlogPath);
	for (size_t i = 0; i < maxObjects; i++)
	{
		const auto obj = rd.next();
		if (!obj) break;
		for (const auto& o : observationsIn(obj))
			if (IS_CLASS(*o, mrpt::obs::CObservationStereoImages) && (!accept || accept(o->sensorLabel)))
				return o->sensorLabel;
	}
	return "";
}

namespace
{
/** Seconds with the nanoseconds rawlogs hold. */
std::string secondsText(double t)
{
	char b[48];
	std::snprintf(b, sizeof b, "%.9f", t);
	return b;
}
}  // namespace

StereoFrameSource::StereoFrameSource(const std::string& rawlogPath, const TStereoFrameSourceOptions& opts)
	: m_reader(rawlogPath), m_opts(opts), m_label(opts.sensorLabel)
{
}

std::string StereoFrameSource::noFramesMessage() const
{
	std::string labels;
	for (const auto& l : m_otherLabels) labels += (labels.empty() ? "" : ", ") + ("'" + l + "'");
	return "'" + path() + "': no stereo observations" +
		   (m_label.empty() ? std::string() : " labelled '" + m_label + "'") +
		   " (other labels: " + (labels.empty() ? "none" : labels) + ")";
}

void StereoFrameChecker::take(const mrpt::obs::CObservationStereoImages::Ptr& st, const std::string& where, TStereoFrame& f)
{
	if (!st->hasImageRight) throw RawlogError(where + "stereo observation without a right image");
	try
	{
		loadExternalImages(*st);
	}
	catch (const std::exception& e)
	{
		throw RawlogError(where + e.what());
	}
	f.obs = st;
	f.sensorLabel = st->sensorLabel;
	f.timestamp = mrpt::Clock::toDouble(st->timestamp);
	// Trajectories, ground-truth lookups and frame rates assume time
	// moves forward: a repeated or earlier time is a damaged input.
	if (m_frames > 0 && !(f.timestamp > m_lastTime))
		throw RawlogError(
			where + "timestamp " + secondsText(f.timestamp) + " s is not after frame " + std::to_string(m_frames - 1) +
			"'s (" + secondsText(m_lastTime) + " s): frame times must increase");
	m_lastTime = f.timestamp;
	f.left = st->imageLeft.asCvMatRef();
	f.right = st->imageRight.asCvMatRef();
	if (f.left.empty() || f.right.empty() || f.left.size() != f.right.size())
		throw RawlogError(
			where + "empty or mismatched left/right images (" + std::to_string(f.left.cols) + "x" +
			std::to_string(f.left.rows) + " / " + std::to_string(f.right.cols) + "x" + std::to_string(f.right.rows) +
			")");
	st->getStereoCameraParams(f.camera);
	if (m_frames == 0)
	{
		try
		{
			m_calib = geometry::TStereoCalib::FromObservation(*st);
		}
		catch (const std::exception& e)
		{
			throw RawlogError(where + e.what());
		}
		m_camera = f.camera;
		m_size = f.left.size();
	}
	else
	{
		if (const auto d = calibrationDifference(m_camera, f.camera); !d.empty())
			throw RawlogError(where + "calibration differs from frame 0: " + d);
		if (f.left.size() != m_size)
			throw RawlogError(
				where + "image size " + std::to_string(f.left.cols) + "x" + std::to_string(f.left.rows) +
				" differs from frame 0 (" + std::to_string(m_size.width) + "x" + std::to_string(m_size.height) + ")");
	}
	f.calib = m_calib;
	m_frames++;
}

bool StereoFrameSource::next(TStereoFrame& f)
{
	using mrpt::obs::CObservationStereoImages;
	for (;;)
	{
		if (m_pending.empty())
		{
			const auto obj = m_reader.next();
			if (!obj) return false;
			m_pending = observationsIn(obj);
			std::reverse(m_pending.begin(), m_pending.end());  // pop_back() in file order
			m_pendingObject = m_reader.index();
			continue;
		}
		const auto o = m_pending.back();
		m_pending.pop_back();
		auto st = std::dynamic_pointer_cast<CObservationStereoImages>(o);
		if (st && m_label.empty() && (!m_opts.acceptLabel || m_opts.acceptLabel(st->sensorLabel)))
			m_label = st->sensorLabel;
		if (!st || st->sensorLabel != m_label)
		{
			if (!o->sensorLabel.empty() && o->sensorLabel != m_label) m_otherLabels.insert(o->sensorLabel);
			continue;
		}
		const std::string where = "'" + path() + "': object #" + std::to_string(m_pendingObject) + ": frame " +
								  std::to_string(m_frames) + " (sensor '" + m_label + "'): ";
		m_check.take(st, where, f);
		f.index = m_frames++;
		f.object = m_pendingObject;
		return true;
	}
}

}  // namespace shadyloc::io

/* ShadyLoc — the frames of one stereo camera as its channels see them. */
#include <shadyloc/filters/ChannelFrameSource.h>
#include <shadyloc/core/Units.h>

#include <algorithm>
#include <chrono>

namespace shadyloc::filters
{
namespace
{
std::string quotedList(const std::vector<std::string>& v)
{
	std::string s;
	for (const auto& x : v) s += (s.empty() ? "'" : ", '") + x + "'";
	return s;
}

using core::msSince;
}  // namespace

bool TChannelPlan::needsColour() const
{
	if (channels.empty()) return true;
	for (const auto& in : inputs)
		if (!in.filtered) return true;
	return false;
}

// ---- the assembler ----------------------------------------------------------------------------
ChannelFrameAssembler::ChannelFrameAssembler(TChannelPlan plan, bool makeChannels)
	: m_plan(std::move(plan)), m_make(makeChannels)
{
	if (m_plan.inputs.size() != m_plan.channels.size())
		throw std::invalid_argument("ChannelFrameAssembler: one input per channel needed");
	// Slot 0 is the colour camera when a channel is made from it; then one
	// slot per label read.
	m_colourSlot = m_plan.needsColour();
	if (m_colourSlot) m_labels.push_back(m_plan.camera);
	for (const auto& in : m_plan.inputs)
		if (in.filtered && std::find(m_labels.begin(), m_labels.end(), in.sensorLabel) == m_labels.end())
			m_labels.push_back(in.sensorLabel);
	m_checks.resize(m_labels.size());
	m_have.resize(m_labels.size());
	m_got.assign(m_labels.size(), false);
}

int ChannelFrameAssembler::slotOf(const std::string& label)
{
	for (size_t s = 0; s < m_labels.size(); s++)
		if (!m_labels[s].empty() && m_labels[s] == label) return int(s);
	// The colour camera, when not named: the first label it may be.
	if (m_colourSlot && m_labels[0].empty() && (!m_plan.acceptCamera || m_plan.acceptCamera(label)))
	{
		m_labels[0] = label;
		return 0;
	}
	return -1;
}

void ChannelFrameAssembler::checkPairing(size_t slot, const io::TStereoFrame& got, const std::string& where) const
{
	for (size_t r = 0; r < m_labels.size(); r++)
	{
		if (r == slot || !m_got[r]) continue;
		const auto& o = m_have[r];
		const std::string other = "'" + m_labels[r] + "''s of the same frame";
		if (got.timestamp != o.timestamp)
			throw io::RawlogError(
				where + "timestamp " + std::to_string(got.timestamp) + " s is not " + other + " (" +
				std::to_string(o.timestamp) + " s): the channels' observations must pair up");
		if (const auto d = io::calibrationDifference(o.camera, got.camera); !d.empty())
			throw io::RawlogError(where + "calibration differs from " + other + ": " + d);
		if (got.left.size() != o.left.size())
			throw io::RawlogError(
				where + "image size " + std::to_string(got.left.cols) + "x" + std::to_string(got.left.rows) +
				" differs from " + other);
		return;	 // the others were checked against this one
	}
}

bool ChannelFrameAssembler::add(
	const mrpt::obs::CObservationStereoImages::Ptr& obs, size_t object, const std::string& where, TChannelFrame& f)
{
	const int s = slotOf(obs->sensorLabel);
	if (s < 0) return false;
	const std::string fw =
		where + ": frame " + std::to_string(m_frames) + " (sensor '" + obs->sensorLabel + "'): ";
	if (m_got[s])
	{
		std::vector<std::string> missing;
		for (size_t r = 0; r < m_labels.size(); r++)
			if (!m_got[r]) missing.push_back(m_labels[r]);
		throw io::RawlogError(
			fw + "the next frame's observation came before this frame's " + quotedList(missing) +
			": the channels' observations must pair up (a partly filtered rawlog?)");
	}
	io::TStereoFrame got;
	m_checks[s].take(obs, fw, got);
	checkPairing(s, got, fw);
	m_have[s] = std::move(got);
	m_got[s] = true;
	for (const bool g : m_got)
		if (!g) return false;
	assemble(object, where, f);
	return true;
}

void ChannelFrameAssembler::assemble(size_t object, const std::string& where, TChannelFrame& f)
{
	const io::TStereoFrame& base = m_have[0];
	f.index = m_frames;
	f.object = object;
	f.timestamp = base.timestamp;
	f.camera = m_colourSlot ? m_labels[0] : m_plan.camera;
	f.calib = base.calib;
	f.stereoCamera = base.camera;
	f.size = base.left.size();
	f.where = where + ": frame " + std::to_string(m_frames) + " (camera '" + f.camera + "'): ";
	f.left = m_colourSlot ? base.left : cv::Mat();
	f.right = m_colourSlot ? base.right : cv::Mat();
	f.obs = m_colourSlot ? base.obs : nullptr;
	f.ms_convert = 0;
	f.channels.assign(m_plan.channels.size(), TChannelPair());
	for (size_t i = 0; i < f.channels.size(); i++)
	{
		auto& c = f.channels[i];
		c.label = m_plan.channels[i].label;
		c.read = m_plan.inputs[i].filtered;
		if (!c.read) continue;
		const auto slot = size_t(std::find(m_labels.begin(), m_labels.end(), m_plan.inputs[i].sensorLabel) - m_labels.begin());
		c.left = m_have[slot].left;
		c.right = m_have[slot].right;
	}
	m_got.assign(m_labels.size(), false);
	m_frames++;
	if (!m_make) return;
	const auto t0 = std::chrono::steady_clock::now();
	for (size_t i = 0; i < f.channels.size(); i++) make(f, i);
	f.ms_convert = msSince(t0);
}

void ChannelFrameAssembler::make(TChannelFrame& f, size_t i) const
{
	auto& c = f.channels.at(i);
	if (!c.left.empty()) return;
	if (f.left.empty()) throw io::RawlogError(f.where + "channel '" + c.label + "': no colour pair to make it from");
	try
	{
		m_plan.channels.at(i).convertPair(f.left, f.right, c.left, c.right);
	}
	catch (const std::exception& e)
	{
		throw io::RawlogError(f.where + "channel '" + c.label + "': " + e.what());
	}
	if (c.left.empty() || c.right.empty())
		throw io::RawlogError(f.where + "channel '" + c.label + "': its filter gave no images");
}

void ChannelFrameAssembler::finish(const std::string& where) const
{
	std::vector<std::string> got, missing;
	for (size_t r = 0; r < m_labels.size(); r++) (m_got[r] ? got : missing).push_back(m_labels[r]);
	if (got.empty()) return;
	throw io::RawlogError(
		where + ": frame " + std::to_string(m_frames) + ": ends with " + quotedList(got) + " but no " +
		quotedList(missing) + ": the channels' observations must pair up (a partly filtered rawlog?)");
}

// ---- the plan ---------------------------------------------------------------------------------
namespace
{
/** A channel made from colour needs the colour camera: refused now, naming
 * the channels, rather than as a rawlog with no frames. */
void checkColourCamera(const std::string& rawlog, const TChannelPlan& p)
{
	const std::string cam = p.camera;
	const auto isColour = cam.empty() ? p.acceptCamera : [cam](const std::string& l) { return l == cam; };
	if (!io::findStereoLabel(rawlog, isColour).empty()) return;
	const std::string any = io::findStereoLabel(rawlog, {});
	std::vector<std::string> made;
	for (size_t i = 0; i < p.channels.size(); i++)
		if (!p.inputs[i].filtered) made.push_back(p.channels[i].label);
	if (any.empty() || made.empty()) return;  // no stereo at all, or no channels: the source's "no frames" message
	throw io::RawlogError(
		"'" + rawlog + "': no colour stereo observations" + (cam.empty() ? std::string() : " labelled '" + cam + "'") +
		" to make channel(s) " + quotedList(made) + " from (its first stereo observations are labelled '" + any +
		"'; a channel the rawlog holds is read, the others are made from colour: filter the colour original with "
		"their filters too)");
}
}  // namespace

TChannelPlan planChannels(const std::string& rawlog, const std::vector<TChannel>& channels, const std::string& camera)
{
	TChannelPlan p;
	p.channels = channels;
	p.camera = camera;
	// Labels that name a derived channel are never the colour camera.
	std::vector<std::string> derived = {"_mono", "_inv", "_lin"};
	for (const auto& ch : channels)
	{
		TChannelInput in = resolveChannelInput(rawlog, ch, p.camera);
		if (in.filtered && p.camera.empty()) p.camera = in.sensorLabel.substr(0, in.sensorLabel.size() - ch.suffix().size());
		derived.insert(derived.end(), in.derivedSuffixes.begin(), in.derivedSuffixes.end());
		p.inputs.push_back(std::move(in));
	}
	p.acceptCamera = io::labelWithoutSuffixes(derived);
	if (p.needsColour()) checkColourCamera(rawlog, p);
	return p;
}

// ---- the rawlog source ------------------------------------------------------------------------
ChannelFrameSource::ChannelFrameSource(
	const std::string& rawlog, const std::vector<TChannel>& channels, const TChannelFrameSourceOptions& o)
	: m_reader(std::make_unique<io::RawlogReader>(rawlog)),
	  m_assembler(planChannels(rawlog, channels, o.camera), o.makeChannels)
{
}

namespace
{
/** Every channel made from the feed's colour camera. */
TChannelPlan colourPlan(const std::string& name, const std::vector<TChannel>& channels, const std::string& camera)
{
	TChannelPlan p;
	p.channels = channels;
	p.camera = camera;
	TChannelInput in;
	in.rawlog = name;
	in.sensorLabel = camera;
	p.inputs.assign(channels.size(), in);
	p.acceptCamera = [](const std::string&) { return true; };
	return p;
}
}  // namespace

ChannelFrameSource::ChannelFrameSource(
	TObjectFeed feed, const std::vector<TChannel>& channels, const TChannelFrameSourceOptions& o)
	: m_feed(std::move(feed)), m_assembler(colourPlan(m_feed.name, channels, o.camera), o.makeChannels)
{
	if (!m_feed.next) throw std::invalid_argument("ChannelFrameSource: a feed without a next()");
}

mrpt::serialization::CSerializable::Ptr ChannelFrameSource::nextObject()
{
	if (m_reader) return m_reader->next();
	auto obj = m_feed.next();
	if (obj) m_objects++;
	return obj;
}

bool ChannelFrameSource::next(TChannelFrame& f)
{
	using mrpt::obs::CObservationStereoImages;
	if (m_ended) return false;
	for (;;)
	{
		if (m_pending.empty())
		{
			const auto obj = nextObject();
			if (!obj)
			{
				m_ended = true;
				m_assembler.finish("'" + path() + "'");
				return false;
			}
			m_pending = io::observationsIn(obj);
			std::reverse(m_pending.begin(), m_pending.end());  // pop_back() in file order
			continue;
		}
		const auto o = m_pending.back();
		m_pending.pop_back();
		const auto st = std::dynamic_pointer_cast<CObservationStereoImages>(o);
		const std::string where = "'" + path() + "': object #" + std::to_string(objectIndex());
		if (st && m_assembler.add(st, objectIndex(), where, f)) return true;
		const auto& ls = m_assembler.labels();
		if (!o->sensorLabel.empty() && std::find(ls.begin(), ls.end(), o->sensorLabel) == ls.end())
			m_otherLabels.insert(o->sensorLabel);
	}
}

std::string ChannelFrameSource::describeInput(size_t i) const
{
	const auto& in = input(i);
	if (in.filtered) return "read from the filtered observations '" + in.sensorLabel + "'";
	const std::string& cam = m_assembler.camera();
	return "made on the fly from the colour camera" + (cam.empty() ? std::string() : " '" + cam + "'");
}

std::string ChannelFrameSource::noFramesMessage() const
{
	std::vector<std::string> named;
	for (const auto& l : m_assembler.labels())
		if (!l.empty()) named.push_back(l);
	std::string others;
	for (const auto& l : m_otherLabels) others += (others.empty() ? "'" : ", '") + l + "'";
	return "'" + path() + "': no stereo observations" + (named.empty() ? std::string() : " labelled " + quotedList(named)) +
		   " (other labels: " + (others.empty() ? "none" : others) + ")";
}

}  // namespace shadyloc::filters

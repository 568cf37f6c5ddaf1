/* ShadyLoc — the concrete observation filters. */
#include <shadyloc/filters/Filters.h>

#include <mrpt/serialization/CArchive.h>

#include <stdexcept>

using namespace shadyloc;

IMPLEMENTS_SERIALIZABLE(CFilterMonochrome, CObservationFilter, shadyloc)
IMPLEMENTS_SERIALIZABLE(CFilterInvariant, CObservationFilter, shadyloc)
IMPLEMENTS_SERIALIZABLE(CFilterLinearise, CObservationFilter, shadyloc)

namespace
{
// Registered when the library loads, in the file that defines the class ids
// and after them: only within one file is the order of initialisation fixed
// (src/Registration.cpp says why).
[[maybe_unused]] const bool filtersRegisteredAtLoad =
	(mrpt::rtti::registerClass(CLASS_ID(CFilterMonochrome)), mrpt::rtti::registerClass(CLASS_ID(CFilterInvariant)),
	 mrpt::rtti::registerClass(CLASS_ID(CFilterLinearise)), true);
}  // namespace

namespace
{
/** An enum stored as a byte, checked against its last value. */
template <class E>
E readEnum(io::BoundedReader& in, const char* field, E last)
{
	const uint8_t v = in.read<uint8_t>(field);
	if (v > static_cast<uint8_t>(last))
		in.fail(field, "value " + std::to_string(v) + " out of range 0.." + std::to_string(static_cast<int>(last)));
	return static_cast<E>(v);
}

void requireColour(const cv::Mat& in)
{
	if (in.channels() != 3)
		throw std::invalid_argument(
			"needs a colour image, got a " + std::to_string(in.channels()) +
			"-channel (grey?) image");
}
}  // namespace

// ---- CFilterMonochrome --------------------------------------------------------
CFilterMonochrome::CFilterMonochrome() { common.output_suffix = "_mono"; }

void CFilterMonochrome::transformImage(const cv::Mat& in, cv::Mat& out) const
{
	image::toMonochrome(in, out, order);
}
void CFilterMonochrome::keys(core::KeyVisitor& v)
{
	v.choice("channel_order", order, image::channelOrderNames(), "memory order of colour input: bgr | rgb");
}
uint8_t CFilterMonochrome::serializeGetVersion() const { return 0; }
void CFilterMonochrome::serializeTo(mrpt::serialization::CArchive& out) const
{
	serializeCommon(out);
	out << static_cast<uint8_t>(order);
}
void CFilterMonochrome::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			auto r = boundedReader(in, version);
			deserializeCommon(r);
			order = readEnum(r, "channel_order", image::ChannelOrder::RGB);
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	};
}

// ---- CFilterInvariant ----------------------------------------------------------
CFilterInvariant::CFilterInvariant()
{
	common.output_suffix = "_inv";
	setParams(image::InvariantParams::FromAlphaBeta(0.4800, 0.5065));
}

void CFilterInvariant::setParams(const image::InvariantParams& p)
{
	m_params = p;
	onOptionsChanged();
}

void CFilterInvariant::onOptionsChanged()
{
	m_transform = std::make_shared<image::InvariantTransform>(m_params);
}

bool CFilterInvariant::sameImagesAs(const CObservationFilter& o) const
{
	const auto* other = dynamic_cast<const CFilterInvariant*>(&o);
	return other && m_params.sameImageAs(other->m_params);
}

void CFilterInvariant::transformImage(const cv::Mat& in, cv::Mat& out) const
{
	requireColour(in);
	m_transform->apply(in, out);
}

void CFilterInvariant::transformImages(
	const std::vector<cv::Mat>& in, std::vector<cv::Mat>& out) const
{
	for (const auto& m : in) requireColour(m);
	out.resize(in.size());
	if (in.size() == 2)
		m_transform->applyPair(in[0], in[1], out[0], out[1], parallel_eyes);
	else
		for (size_t i = 0; i < in.size(); i++) m_transform->apply(in[i], out[i]);
}

void CFilterInvariant::keys(core::KeyVisitor& v)
{
	m_params.keys(v);
	v("parallel_eyes", parallel_eyes, "", core::Range::any(), "transform left and right on two threads");
}

void CFilterInvariant::validate() const { m_params.validate(); }

void CFilterInvariant::loadSpecificOptions(core::SettingsSection& s)
{
	image::InvariantParams p = m_params;
	p.readFrom(s);	// validates
	core::readKeys(s, *this);  // parallel_eyes (and the parameters again, as written)
	m_params = p;  // the parameters as readFrom() made them
}

std::vector<std::string> CFilterInvariant::keysNotDecidingImages() const
{
	std::vector<std::string> out = {"parallel_eyes"};
	if (m_params.linearisation != image::Linearisation::Gamma) out.push_back("gamma");
	if (!m_params.hasCompressedTails())
		out.insert(out.end(), {"knee_low", "knee_high", "tail_slope_low", "tail_slope_high"});
	// As for the tails: maps made before the chroma handling keep their recorded text.
	if (m_params.chroma_handling == image::ChromaHandling::None) out.push_back("chroma_handling");
	if (m_params.chroma_handling != image::ChromaHandling::Prefilter) out.push_back("chroma_sigma_px");
	return out;
}

// 0: no compressed tails; 1: knees and tail slopes after parallel_eyes;
// 2: chroma handling and its sigma after the tail slopes.
uint8_t CFilterInvariant::serializeGetVersion() const { return 2; }
void CFilterInvariant::serializeTo(mrpt::serialization::CArchive& out) const
{
	serializeCommon(out);
	out << m_params.alpha << m_params.beta << static_cast<uint8_t>(m_params.order)
		<< static_cast<uint8_t>(m_params.linearisation) << m_params.gamma << m_params.scale
		<< m_params.offset << parallel_eyes << m_params.knee_low << m_params.knee_high << m_params.tail_slope_low
		<< m_params.tail_slope_high << static_cast<uint8_t>(m_params.chroma_handling) << m_params.chroma_sigma_px;
}
void CFilterInvariant::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		case 1:
		case 2:
		{
			auto r = boundedReader(in, version);
			deserializeCommon(r);
			image::InvariantParams p;
			r.read(p.alpha, "alpha");
			r.read(p.beta, "beta");
			p.order = readEnum(r, "channel_order", image::ChannelOrder::RGB);
			p.linearisation = readEnum(r, "linearisation", image::Linearisation::Gamma);
			r.read(p.gamma, "gamma");
			r.read(p.scale, "scale");
			r.read(p.offset, "offset");
			r.read(parallel_eyes, "parallel_eyes");
			if (version >= 1)
			{
				r.read(p.knee_low, "knee_low");
				r.read(p.knee_high, "knee_high");
				r.read(p.tail_slope_low, "tail_slope_low");
				r.read(p.tail_slope_high, "tail_slope_high");
			}
			if (version >= 2)
			{
				p.chroma_handling = readEnum(r, "chroma_handling", image::ChromaHandling::ChromaResolution);
				r.read(p.chroma_sigma_px, "chroma_sigma_px");
			}
			try
			{
				p.validate();
			}
			catch (const std::exception& e)
			{
				r.fail("parameters", e.what());
			}
			m_params = p;
			onOptionsChanged();
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	};
}

// ---- CFilterLinearise ----------------------------------------------------------
CFilterLinearise::CFilterLinearise() { common.output_suffix = "_lin"; }

void CFilterLinearise::transformImage(const cv::Mat& in, cv::Mat& out) const
{
	requireColour(in);
	image::toLinear8(in, out, linearisation, gamma);
}
void CFilterLinearise::keys(core::KeyVisitor& v)
{
	v.choice("linearisation", linearisation, image::linearisationNames(), "none | srgb | gamma");
	v("gamma", gamma, "", core::Range::any(), "exponent with linearisation = gamma");
}
void CFilterLinearise::validate() const
{
	CObservationFilter::validate();
	if (linearisation == image::Linearisation::Gamma && !(gamma > 0 && gamma < 10))
		throw std::invalid_argument("gamma: '" + core::formatSetting(gamma) + "' must be in (0,10)");
}
std::vector<std::string> CFilterLinearise::keysNotDecidingImages() const
{
	if (linearisation == image::Linearisation::Gamma) return {};
	return {"gamma"};
}

uint8_t CFilterLinearise::serializeGetVersion() const { return 0; }
void CFilterLinearise::serializeTo(mrpt::serialization::CArchive& out) const
{
	serializeCommon(out);
	out << static_cast<uint8_t>(linearisation) << gamma;
}
void CFilterLinearise::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			auto r = boundedReader(in, version);
			deserializeCommon(r);
			linearisation = readEnum(r, "linearisation", image::Linearisation::Gamma);
			r.read(gamma, "gamma");
			if (linearisation == image::Linearisation::Gamma && !(gamma > 0 && gamma < 10))
				r.fail("gamma", std::to_string(gamma) + ": must be in (0,10)");
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	};
}

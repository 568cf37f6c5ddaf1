/* ShadyLoc — the concrete observation filters. */
#include <shadyloc/filters/Filters.h>

#include <mrpt/serialization/CArchive.h>

#include <ostream>
#include <stdexcept>

using namespace shadyloc;

IMPLEMENTS_SERIALIZABLE(CFilterMonochrome, CObservationFilter, shadyloc)
IMPLEMENTS_SERIALIZABLE(CFilterInvariant, CObservationFilter, shadyloc)
IMPLEMENTS_SERIALIZABLE(CFilterLinearise, CObservationFilter, shadyloc)

namespace
{
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
void CFilterMonochrome::loadSpecificOptions(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	order = image::parseChannelOrder(c.read_string(s, "channel_order", image::toString(order)));
}
void CFilterMonochrome::specificOptionsAsIni(std::ostream& out) const
{
	out << "; memory order of colour input\nchannel_order = " << image::toString(order) << "\n";
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
			deserializeCommon(in);
			uint8_t o;
			in >> o;
			order = static_cast<image::ChannelOrder>(o);
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

void CFilterInvariant::loadSpecificOptions(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	image::InvariantParams p = m_params;
	// Either three peak wavelengths (beta = 1 - alpha), or alpha and beta.
	const double l1 = c.read_double(s, "peak_wavelength_blue_nm", 0);
	const double l2 = c.read_double(s, "peak_wavelength_green_nm", 0);
	const double l3 = c.read_double(s, "peak_wavelength_red_nm", 0);
	const bool byWavelength = l1 > 0 || l2 > 0 || l3 > 0;
	if (byWavelength)
	{
		if (c.keyExists(s, "alpha") || c.keyExists(s, "beta"))
			throw std::invalid_argument(
				"give either peak_wavelength_*_nm or alpha/beta, not both");
		const auto w = image::InvariantParams::FromWavelengths(l1, l2, l3);
		p.alpha = w.alpha;
		p.beta = w.beta;
	}
	else
	{
		p.alpha = c.read_double(s, "alpha", p.alpha);
		p.beta = c.read_double(s, "beta", p.beta);
	}
	p.order = image::parseChannelOrder(c.read_string(s, "channel_order", image::toString(p.order)));
	p.linearisation = image::parseLinearisation(
		c.read_string(s, "linearisation", image::toString(p.linearisation)));
	p.gamma = c.read_double(s, "gamma", p.gamma);
	p.scale = c.read_double(s, "scale", p.scale);
	p.offset = c.keyExists(s, "offset") ? c.read_double(s, "offset", 0) : p.defaultOffset();
	parallel_eyes = c.read_bool(s, "parallel_eyes", parallel_eyes);
	p.validate();
	m_params = p;
}

void CFilterInvariant::specificOptionsAsIni(std::ostream& out) const
{
	out.precision(10);
	out << "; weights of log(blue) and log(red)\nalpha = " << m_params.alpha << "\n"
		<< "beta = " << m_params.beta << "\n"
		<< "channel_order = " << image::toString(m_params.order) << "\n"
		<< "; none|srgb|gamma\nlinearisation = " << image::toString(m_params.linearisation) << "\n"
		<< "gamma = " << m_params.gamma << "\n"
		<< "; grey levels per unit log response; log units added before scaling\n"
		<< "scale = " << m_params.scale << "\n"
		<< "offset = " << m_params.offset << "\n"
		<< "parallel_eyes = " << (parallel_eyes ? "true" : "false") << "\n";
}

uint8_t CFilterInvariant::serializeGetVersion() const { return 0; }
void CFilterInvariant::serializeTo(mrpt::serialization::CArchive& out) const
{
	serializeCommon(out);
	out << m_params.alpha << m_params.beta << static_cast<uint8_t>(m_params.order)
		<< static_cast<uint8_t>(m_params.linearisation) << m_params.gamma << m_params.scale
		<< m_params.offset << parallel_eyes;
}
void CFilterInvariant::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			deserializeCommon(in);
			uint8_t o, l;
			in >> m_params.alpha >> m_params.beta >> o >> l >> m_params.gamma >>
				m_params.scale >> m_params.offset >> parallel_eyes;
			m_params.order = static_cast<image::ChannelOrder>(o);
			m_params.linearisation = static_cast<image::Linearisation>(l);
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
void CFilterLinearise::loadSpecificOptions(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	linearisation = image::parseLinearisation(
		c.read_string(s, "linearisation", image::toString(linearisation)));
	gamma = c.read_double(s, "gamma", gamma);
	if (linearisation == image::Linearisation::Gamma && !(gamma > 0 && gamma < 10))
		throw std::invalid_argument("gamma = " + std::to_string(gamma) + ": must be in (0,10)");
}
void CFilterLinearise::specificOptionsAsIni(std::ostream& out) const
{
	out << "; none|srgb|gamma\nlinearisation = " << image::toString(linearisation) << "\n"
		<< "gamma = " << gamma << "\n";
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
			deserializeCommon(in);
			uint8_t l;
			in >> l >> gamma;
			linearisation = static_cast<image::Linearisation>(l);
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	};
}

// Registered here, after this file's class ids are initialised (one file is
// initialised in order of definition): the ids hold a std::function, so they
// are initialised at load time, in an order across files that the compiler
// chooses (clang: after core/Registration.cpp).
namespace
{
/** A static object, not MRPT_INITIALIZER (a constructor function, which
 * clang may run before this file's dynamic initialisation). */
struct TRegister
{
	TRegister()
	{
		using namespace mrpt::rtti;
		registerClass(CLASS_ID(shadyloc::CFilterMonochrome));
		registerClass(CLASS_ID(shadyloc::CFilterInvariant));
		registerClass(CLASS_ID(shadyloc::CFilterLinearise));
	}
} s_register;
}  // namespace

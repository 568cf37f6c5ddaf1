/* ShadyLoc — observation filter base. */
#include <shadyloc/filters/CObservationFilter.h>

#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/string_utils.h>

#include <sstream>
#include <stdexcept>

using namespace shadyloc;

IMPLEMENTS_VIRTUAL_SERIALIZABLE(CObservationFilter, CSerializable, shadyloc)

void CObservationFilter::loadFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	common.output_suffix = cfg.read_string(section, "output_suffix", common.output_suffix);
	common.sensor_labels = cfg.read_string(section, "sensor_labels", common.sensor_labels);
	if (common.output_suffix.empty())
		throw std::invalid_argument(
			"[" + section + "] output_suffix: must not be empty (the derived channel "
			"would take the source's sensor label)");
	try
	{
		loadSpecificOptions(cfg, section);
		onOptionsChanged();
	}
	catch (const std::exception& e)
	{
		throw std::invalid_argument("[" + section + "] " + e.what());
	}
}

std::string CObservationFilter::optionsAsIni() const
{
	std::ostringstream s;
	s << "class = " << GetRuntimeClass()->className << "\n";
	s << "output_suffix = " << common.output_suffix << "\n";
	s << "sensor_labels = " << common.sensor_labels << "\n";
	specificOptionsAsIni(s);
	return s.str();
}

bool CObservationFilter::accepts(const mrpt::obs::CObservation& obs) const
{
	using namespace mrpt::obs;
	if (!IS_CLASS(obs, CObservationStereoImages) && !IS_CLASS(obs, CObservationImage))
		return false;
	if (common.sensor_labels.empty()) return true;
	std::vector<std::string> labels;
	mrpt::system::tokenize(common.sensor_labels, ", \t", labels);
	for (const auto& l : labels)
		if (l == obs.sensorLabel) return true;
	return false;
}

void CObservationFilter::transformImages(
	const std::vector<cv::Mat>& in, std::vector<cv::Mat>& out) const
{
	out.resize(in.size());
	for (size_t i = 0; i < in.size(); i++) transformImage(in[i], out[i]);
}

mrpt::obs::CObservation::Ptr CObservationFilter::apply(const mrpt::obs::CObservation& obs) const
{
	using namespace mrpt::obs;
	const std::string who = GetRuntimeClass()->className;
	auto run = [&](std::vector<const mrpt::img::CImage*> eyes, const char* const* names) {
		std::vector<cv::Mat> in, out;
		for (size_t i = 0; i < eyes.size(); i++)
		{
			if (eyes[i]->isEmpty())
				throw std::invalid_argument(
					who + ": sensor '" + obs.sensorLabel + "': " + names[i] + " image is empty");
			in.push_back(eyes[i]->asCvMatRef());
		}
		try
		{
			transformImages(in, out);
		}
		catch (const std::exception& e)
		{
			throw std::invalid_argument(
				who + ": sensor '" + obs.sensorLabel + "': " + e.what());
		}
		return out;
	};

	if (const auto* st = dynamic_cast<const CObservationStereoImages*>(&obs))
	{
		static const char* names[] = {"left", "right"};
		std::vector<const mrpt::img::CImage*> eyes = {&st->imageLeft};
		if (st->hasImageRight) eyes.push_back(&st->imageRight);
		const auto out = run(eyes, names);
		// The derived images are fresh Mats owned by `out`: share, don't copy.
		auto d = CObservationStereoImages::Create();
		d->timestamp = st->timestamp;
		d->sensorLabel = st->sensorLabel + common.output_suffix;
		d->cameraPose = st->cameraPose;
		d->leftCamera = st->leftCamera;
		d->rightCamera = st->rightCamera;
		d->rightCameraPose = st->rightCameraPose;
		d->imageLeft = mrpt::img::CImage(out[0], mrpt::img::SHALLOW_COPY);
		d->hasImageRight = st->hasImageRight;
		if (st->hasImageRight) d->imageRight = mrpt::img::CImage(out[1], mrpt::img::SHALLOW_COPY);
		d->hasImageDisparity = false;
		return d;
	}
	if (const auto* im = dynamic_cast<const CObservationImage*>(&obs))
	{
		static const char* names[] = {""};
		const auto out = run({&im->image}, names);
		auto d = CObservationImage::Create();
		d->timestamp = im->timestamp;
		d->sensorLabel = im->sensorLabel + common.output_suffix;
		d->cameraPose = im->cameraPose;
		d->cameraParams = im->cameraParams;
		d->image = mrpt::img::CImage(out[0], mrpt::img::SHALLOW_COPY);
		return d;
	}
	throw std::invalid_argument(
		who + ": observation '" + obs.sensorLabel + "' of class " +
		obs.GetRuntimeClass()->className + " is not a camera observation");
}

void CObservationFilter::serializeCommon(mrpt::serialization::CArchive& out) const
{
	out << common.output_suffix << common.sensor_labels;
}
void CObservationFilter::deserializeCommon(mrpt::serialization::CArchive& in)
{
	in >> common.output_suffix >> common.sensor_labels;
}

// Registered after this file's class id is initialised (see Filters.cpp).
namespace
{
/** A static object, not MRPT_INITIALIZER (a constructor function, which
 * clang may run before this file's dynamic initialisation). */
struct TRegister
{
	TRegister()
	{
		mrpt::rtti::registerClass(CLASS_ID(shadyloc::CObservationFilter));
	}
} s_register;
}  // namespace

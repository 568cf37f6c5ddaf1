/* ShadyLoc — observation filter base. */
#include <shadyloc/filters/CObservationFilter.h>

#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/string_utils.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

using namespace shadyloc;

IMPLEMENTS_VIRTUAL_SERIALIZABLE(CObservationFilter, CSerializable, shadyloc)

void CObservationFilter::loadFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	core::SettingsSection s(cfg, section);
	s.alsoKnown({"class"});	// read by FilterPipeline::FromConfig
	s.read("output_suffix", common.output_suffix);
	s.read("sensor_labels", common.sensor_labels);
	if (common.output_suffix.empty())
		s.fail("output_suffix", "must not be empty (the derived channel would take the source's sensor label)");
	loadSpecificOptions(s);
	s.finish();
	try
	{
		onOptionsChanged();
	}
	catch (const std::exception& e)
	{
		throw core::SettingsError(s.where() + " " + e.what());
	}
}

std::string CObservationFilter::optionsAsIni() const
{
	std::ostringstream s;
	core::SettingsWriter w(s);
	w.value("class", GetRuntimeClass()->className);
	w.value("output_suffix", common.output_suffix);
	w.value("sensor_labels", common.sensor_labels);
	specificOptionsAsIni(s);
	return s.str();
}

std::string CObservationFilter::imageOptionsAsIni() const
{
	// The specific options without their comments.
	std::ostringstream s;
	specificOptionsAsIni(s);
	std::istringstream in(s.str());
	std::string line, out;
	while (std::getline(in, line))
	{
		const std::string t = mrpt::system::trim(line);
		if (t.empty() || t[0] == ';' || t[0] == '#') continue;
		out += t + "\n";
	}
	return out;
}

std::string CObservationFilter::describe() const
{
	// The specific options, comments dropped, on one line.
	std::ostringstream s;
	specificOptionsAsIni(s);
	std::istringstream in(s.str());
	std::string line, out;
	while (std::getline(in, line))
	{
		line = mrpt::system::trim(line);
		if (line.empty() || line[0] == ';' || line[0] == '#') continue;
		line.erase(std::remove(line.begin(), line.end(), ' '), line.end());
		out += (out.empty() ? "" : " ") + line;
	}
	return out;
}

bool CObservationFilter::sameImagesAs(const CObservationFilter& o) const
{
	if (GetRuntimeClass() != o.GetRuntimeClass()) return false;
	std::ostringstream a, b;
	specificOptionsAsIni(a);
	o.specificOptionsAsIni(b);
	return a.str() == b.str();
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
io::BoundedReader CObservationFilter::boundedReader(
	mrpt::serialization::CArchive& in, uint8_t version) const
{
	return io::BoundedReader(
		in, std::string(GetRuntimeClass()->className) + " (version " + std::to_string(version) + ")",
		kMaxSerializedBytes);
}
void CObservationFilter::deserializeCommon(io::BoundedReader& in)
{
	in.readString(common.output_suffix, "output_suffix", kMaxOptionStringBytes);
	in.readString(common.sensor_labels, "sensor_labels", kMaxOptionStringBytes);
}

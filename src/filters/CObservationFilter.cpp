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

namespace
{
// Registered when the library loads, after its class id (src/Registration.cpp).
[[maybe_unused]] const bool filterBaseRegisteredAtLoad = (mrpt::rtti::registerClass(CLASS_ID(CObservationFilter)), true);
}  // namespace

void CObservationFilter::TCommonOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	// No comments: a filtered rawlog records these lines (tests/golden/filter_record.txt).
	v("output_suffix", output_suffix, "", Range::any(), "");
	v("sensor_labels", sensor_labels, "", Range::any(), "");
}

void CObservationFilter::TCommonOptions::validate() const
{
	if (output_suffix.empty())
		throw std::invalid_argument(
			"output_suffix: must not be empty (the derived channel would take the source's sensor label)");
}

void CObservationFilter::validate() const { core::checkKeys(*this); }

void CObservationFilter::loadFromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
	core::SettingsSection s(cfg, section);
	s.alsoKnown({"class"});	// read by FilterPipeline::FromConfig
	core::readKeys(s, common);
	core::validateAt(s, [&] { common.validate(); });
	loadSpecificOptions(s);
	s.finish();
	core::validateAt(s, [&] { onOptionsChanged(); });
}

void CObservationFilter::loadSpecificOptions(core::SettingsSection& s)
{
	core::readKeys(s, *this);
	core::validateAt(s, [&] { validate(); });
}

std::string CObservationFilter::optionsAsIni() const
{
	std::ostringstream s;
	core::SettingsWriter w(s);
	w.value("class", GetRuntimeClass()->className);
	core::writeKeys(w, common);
	core::writeKeys(w, *this);
	return s.str();
}

std::vector<std::string> CObservationFilter::specificOptionLines(const std::vector<std::string>& leaveOut) const
{
	std::ostringstream s;
	core::SettingsWriter w(s);
	core::KeyWriter v(w, leaveOut);
	core::keysOf(*this).keys(v);
	std::istringstream in(s.str());
	std::string line;
	std::vector<std::string> lines;
	while (std::getline(in, line))
	{
		line = mrpt::system::trim(line);
		if (!line.empty() && line[0] != ';' && line[0] != '#') lines.push_back(line);
	}
	return lines;
}

std::string CObservationFilter::imageOptionsAsIni() const
{
	std::string out;
	for (const auto& l : specificOptionLines(keysNotDecidingImages())) out += l + "\n";
	return out;
}

std::string CObservationFilter::describe() const
{
	// The own options on one line.
	std::string out;
	for (auto l : specificOptionLines())
	{
		l.erase(std::remove(l.begin(), l.end(), ' '), l.end());
		out += (out.empty() ? "" : " ") + l;
	}
	return out;
}

bool CObservationFilter::sameImagesAs(const CObservationFilter& o) const
{
	return GetRuntimeClass() == o.GetRuntimeClass() && specificOptionLines() == o.specificOptionLines();
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

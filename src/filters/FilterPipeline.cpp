/* ShadyLoc — filter pipeline and streaming rawlog processor. */
#include <shadyloc/core/Settings.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/system/CTicTac.h>
#include <mrpt/system/string_utils.h>

#include <filesystem>
#include <map>
#include <set>
#include <sstream>

using namespace shadyloc;
using namespace shadyloc::filters;

FilterPipeline FilterPipeline::Default()
{
	FilterPipeline p;
	p.filters.push_back(CFilterMonochrome::Create());
	p.filters.push_back(CFilterInvariant::Create());
	p.labels = {"mono", "invariant"};
	return p;
}

FilterPipeline FilterPipeline::FromConfigFile(const std::string& iniPath)
{
	if (!std::filesystem::is_regular_file(iniPath))
		throw std::invalid_argument("'" + iniPath + "': no such config file");
	mrpt::config::CConfigFile cfg(iniPath);
	return FromConfig(cfg, iniPath);
}

FilterPipeline FilterPipeline::FromConfig(
	const mrpt::config::CConfigFileBase& cfg, const std::string& what)
{
	std::vector<std::string> sections;
	try
	{
		core::SettingsSection top(cfg, kPipelineSection, what);
		std::string list;
		top.read("pipeline", list);
		top.finish();
		if (list.empty()) top.fail("pipeline", "missing or empty");
		mrpt::system::tokenize(list, ", \t", sections);
		// A section not in the pipeline would be ignored whole: a misspelling.
		std::vector<std::string> known = {kPipelineSection};
		known.insert(known.end(), sections.begin(), sections.end());
		core::checkSections(cfg, known, "filter config (sections must be listed in [filters] pipeline)");
	}
	catch (const std::exception& e)
	{
		throw core::SettingsError(core::withSource(what, e.what()));
	}
	return FromSections(cfg, sections, what);
}

FilterPipeline FilterPipeline::FromSections(
	const mrpt::config::CConfigFileBase& cfg, const std::vector<std::string>& sections, const std::string& what)
{
	try
	{
		FilterPipeline p;
		for (const auto& sect : sections)
		{
			core::SettingsSection s(cfg, sect, what);
			std::string cls;
			s.read("class", cls);
			if (cls.empty()) s.fail("class", "missing (section listed in pipeline)");
			if (cls.find("::") == std::string::npos) cls = "shadyloc::" + cls;
			auto obj = mrpt::rtti::classFactory(cls);
			auto f = std::dynamic_pointer_cast<CObservationFilter>(obj);
			if (!f) s.fail("class", "'" + cls + "' is not a registered observation filter");
			f->loadFromConfig(cfg, sect);
			p.filters.push_back(f);
			p.labels.push_back(sect);
		}
		// One derived channel, one filter: two filters with the same suffix for
		// the same sensor would write two streams under one label.
		auto labelsOf = [](const CObservationFilter& f) {
			std::vector<std::string> v;
			mrpt::system::tokenize(f.common.sensor_labels, ", \t", v);
			return std::set<std::string>(v.begin(), v.end());
		};
		for (size_t i = 0; i < p.filters.size(); i++)
			for (size_t j = i + 1; j < p.filters.size(); j++)
			{
				const auto& a = *p.filters[i];
				const auto& b = *p.filters[j];
				if (a.common.output_suffix != b.common.output_suffix) continue;
				const auto la = labelsOf(a), lb = labelsOf(b);
				std::string shared;
				if (la.empty() || lb.empty())
					shared = "every camera";
				else
					for (const auto& l : la)
						if (lb.count(l)) shared += (shared.empty() ? "" : ", ") + l;
				if (shared.empty()) continue;
				throw std::invalid_argument(
					"[" + p.labels[i] + "] and [" + p.labels[j] + "] both write the channel '<sensor>" +
					a.common.output_suffix + "' (output_suffix = " + a.common.output_suffix + ", sensors: " + shared +
					"): give one of them another output_suffix");
			}
		return p;
	}
	catch (const std::exception& e)
	{
		throw core::SettingsError(core::withSource(what, e.what()));
	}
}

std::string FilterPipeline::asIni() const
{
	std::ostringstream s, list;
	for (size_t i = 0; i < filters.size(); i++)
	{
		const std::string sect = label(i);
		list << (i ? " " : "") << sect;
		s << "\n[" << sect << "]\n" << filters[i]->optionsAsIni();
	}
	return "[" + std::string(kPipelineSection) + "]\npipeline = " + list.str() + "\n" + s.str();
}

std::string FilterPipeline::label(size_t i) const
{
	return i < labels.size() && !labels[i].empty() ? labels[i] : "filter" + std::to_string(i);
}

RawlogFilterProcessor::RawlogFilterProcessor() : mrpt::system::COutputLogger("shadyloc.filter") {}

FilterRunStats RawlogFilterProcessor::run(
	const std::string& inPath, const std::string& outPath, const FilterPipeline& pipeline)
{
	using namespace mrpt::obs;
	FilterRunStats st;
	mrpt::system::CTicTac timer, progressTimer;
	io::RawlogReader reader(inPath);
	// The output (rawlog and images folder) may replace none of the inputs.
	io::OutputTransaction outputs;
	outputs.addInput(inPath, "input rawlog");
	const std::string inImages = io::imagesDirFor(inPath);
	if (std::filesystem::is_directory(inImages)) outputs.addInput(inImages, "images folder of the input");
	for (const auto& f : otherInputs) outputs.addInput(f, "input '" + f + "'");
	io::RawlogWriter writer(outPath, externalImages, &outputs);

	// Labels seen in the input and labels derived: a derived channel may not
	// duplicate a stream the input holds (a filtered rawlog filtered again).
	std::set<std::string> inputLabels, derivedLabels;
	std::vector<size_t> accepted(pipeline.filters.size(), 0);
	auto sectionOf = [&](size_t i) {
		return i < pipeline.labels.size() ? "[" + pipeline.labels[i] + "]" : "filter #" + std::to_string(i);
	};
	auto clash = [&](const std::string& label) {
		return io::RawlogError(reader.where(
			"the input already holds observations labelled '" + label +
			"', the channel this pipeline derives (is it filtered already? filter the original, or change "
			"output_suffix)"));
	};
	// Input observations are written unchanged: their external images must
	// exist beside the output too.
	auto carry = [&](CObservation& o) {
		if (!inputLabels.count(o.sensorLabel))
		{
			if (derivedLabels.count(o.sensorLabel)) throw clash(o.sensorLabel);
			inputLabels.insert(o.sensorLabel);
		}
		try
		{
			if (auto* s = dynamic_cast<CObservationStereoImages*>(&o))
			{
				writer.carryExternalImage(s->imageLeft, inImages);
				if (s->hasImageRight) writer.carryExternalImage(s->imageRight, inImages);
				if (s->hasImageDisparity) writer.carryExternalImage(s->imageDisparity, inImages);
			}
			else if (auto* im = dynamic_cast<CObservationImage*>(&o))
				writer.carryExternalImage(im->image, inImages);
		}
		catch (const io::RawlogError& e)
		{
			throw io::RawlogError(reader.where(e.what()));
		}
	};

	// The record takes the first observation's timestamp, so that it does not
	// stretch the rawlog's time span in tools that report one.
	auto record = CObservationComment::Create();
	record->sensorLabel = kRecordLabel;
	record->text = std::string(kRecordHeader) + "\n" + pipeline.asIni();
	bool recordWritten = false;
	size_t imageCounter = 0;

	// Derived channels of one observation, with external images if asked.
	auto derive = [&](const CObservation::Ptr& obs) {
		std::vector<CObservation::Ptr> out;
		bool any = false;
		for (size_t fi = 0; fi < pipeline.filters.size(); fi++)
		{
			const auto& f = pipeline.filters[fi];
			if (!f->accepts(*obs)) continue;
			accepted[fi]++;
			CObservation::Ptr d;
			try
			{
				if (!any) io::loadExternalImages(*obs);
				any = true;
				d = f->apply(*obs);
			}
			catch (const std::exception& e)
			{
				throw io::RawlogError(reader.where(e.what() + io::externalImagesOf(*obs)));
			}
			if (inputLabels.count(d->sensorLabel)) throw clash(d->sensorLabel);
			derivedLabels.insert(d->sensorLabel);
			if (writer.externalImages())
			{
				const std::string stem = d->sensorLabel + "_" + std::to_string(imageCounter);
				if (auto* s = dynamic_cast<CObservationStereoImages*>(d.get()))
				{
					writer.externalise(s->imageLeft, stem + "_left.png");
					if (s->hasImageRight) writer.externalise(s->imageRight, stem + "_right.png");
				}
				else if (auto* im = dynamic_cast<CObservationImage*>(d.get()))
					writer.externalise(im->image, stem + ".png");
			}
			out.push_back(d);
		}
		if (any) st.observationsFiltered++;
		imageCounter++;
		st.derivedObservations += out.size();
		return out;
	};

	MRPT_LOG_INFO_STREAM("Filtering '" << inPath << "' -> '" << outPath << "' with "
									   << pipeline.filters.size() << " filter(s)");
	while (auto obj = reader.next())
	{
		st.objectsIn++;
		if (auto sf = std::dynamic_pointer_cast<CSensoryFrame>(obj))
		{
			auto outSf = CSensoryFrame::Create();
			if (!recordWritten && sf->size() > 0)
			{
				record->timestamp = (*sf->begin())->timestamp;
				outSf->insert(record);
				recordWritten = true;
			}
			for (const auto& o : *sf)
			{
				// Derive first: carrying may rename the input's external
				// images to the output's folder, which the filters read from.
				const auto derived = derive(o);
				carry(*o);
				outSf->insert(o);
				for (const auto& d : derived) outSf->insert(d);
			}
			writer.write(*outSf);
		}
		else if (auto obs = std::dynamic_pointer_cast<CObservation>(obj))
		{
			if (!recordWritten)
			{
				record->timestamp = obs->timestamp;
				writer.write(*record);
				recordWritten = true;
			}
			const auto derived = derive(obs);
			carry(*obs);
			writer.write(*obs);
			for (const auto& d : derived) writer.write(*d);
		}
		else
			writer.write(*obj);	 // actions and anything else: untouched

		if (progressTimer.Tac() > progressPeriodSeconds)
		{
			progressTimer.Tic();
			MRPT_LOG_INFO_FMT(
				"  %5.1f%%  %zu objects, %zu frames filtered, %.1f frames/s",
				100.0 * reader.progress(), st.objectsIn, st.observationsFiltered,
				st.observationsFiltered / std::max(1e-9, timer.Tac()));
		}
	}
	if (st.objectsIn == 0)
		throw io::RawlogError("'" + inPath + "': the rawlog holds no objects");
	// A filter restricted to sensors the rawlog does not have did nothing:
	// most likely a misspelt label.
	for (size_t fi = 0; fi < pipeline.filters.size(); fi++)
		if (accepted[fi] == 0 && !pipeline.filters[fi]->common.sensor_labels.empty())
		{
			std::string labels;
			for (const auto& l : inputLabels) labels += (labels.empty() ? "'" : ", '") + l + "'";
			throw std::invalid_argument(
				sectionOf(fi) + " sensor_labels = " + pipeline.filters[fi]->common.sensor_labels +
				": matches no camera observation in '" + inPath + "' (its labels: " +
				(labels.empty() ? std::string("none") : labels) + ")");
		}
	st.objectsOut = writer.written();
	writer.commit();
	outputs.commit();
	st.seconds = timer.Tac();
	MRPT_LOG_INFO_FMT(
		"Done: %zu objects in, %zu out, %zu camera observations filtered, %zu channels "
		"added, %.2f s",
		st.objectsIn, st.objectsOut, st.observationsFiltered, st.derivedObservations, st.seconds);
	return st;
}

std::string shadyloc::filters::readPipelineRecord(const std::string& rawlogPath)
{
	io::RawlogReader reader(rawlogPath);
	for (int i = 0; i < 3; i++)
	{
		auto obj = reader.next();
		if (!obj) break;
		for (const auto& o : io::observationsIn(obj))
			if (auto c = std::dynamic_pointer_cast<mrpt::obs::CObservationComment>(o);
				c && c->text.rfind(kRecordHeader, 0) == 0)
				return c->text.substr(std::string(kRecordHeader).size() + 1);
	}
	return {};
}

/* Persistent formats: every registered shadyloc:: class round-trips through
 * MRPT serialisation to identical bytes; golden files pin the byte layout of
 * each format (classes, the filter record); reads are bounded (the keyframe
 * map's own bounded reads: test_map_format.cpp).
 *
 * Golden files live in tests/golden/. After a deliberate format change (with
 * its version bump), regenerate them with
 *   SHADYLOC_UPDATE_GOLDEN=1 build/tests/shadyloc_tests --gtest_filter='FormatsGolden.*'
 * (the run rewrites the files and fails on purpose), then review
 * `git diff tests/golden` and commit. */
#include <shadyloc/Registration.h>
#include <shadyloc/filters/FilterPipeline.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/io/Rawlog.h>
#include <shadyloc/map/CKeyframeMap.h>

#include "../support/TestSupport.h"

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

using namespace shadyloc;
using test::Bytes;

namespace
{
const std::string kGoldenDir = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden";

void writeGoldenFile(const std::string& path, const Bytes& b)
{
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
	if (!f) throw std::runtime_error("cannot write '" + path + "'");
}
Bytes asBytes(const std::string& s) { return Bytes(s.begin(), s.end()); }

Bytes memoryBytes(const mrpt::io::CMemoryStream& m)
{
	const auto* p = static_cast<const uint8_t*>(m.getRawBufferData());
	return Bytes(p, p + m.getTotalBytesCount());
}

/** The object as MRPT stores it in a rawlog (class name, version, data). */
Bytes serialise(const mrpt::serialization::CSerializable& o)
{
	mrpt::io::CMemoryStream m;
	auto ar = mrpt::serialization::archiveFrom(m);
	ar << o;
	return memoryBytes(m);
}
mrpt::serialization::CSerializable::Ptr deserialise(const Bytes& b)
{
	mrpt::io::CMemoryStream m;
	m.assignMemoryNotOwn(b.data(), b.size());
	auto ar = mrpt::serialization::archiveFrom(m);
	auto o = ar.ReadObject();
	EXPECT_EQ(m.getPosition(), b.size()) << "the reader left bytes unread";
	return o;
}

// ---- fixed, populated objects: every field non-default and distinct --------
// Distinct values make a swap of two fields in serializeTo change the bytes.

void populateCommon(CObservationFilter& f, const char* suffix, const char* labels)
{
	f.common.output_suffix = suffix;
	f.common.sensor_labels = labels;
}
CFilterMonochrome::Ptr populatedMonochrome()
{
	auto f = CFilterMonochrome::Create();
	populateCommon(*f, "_m0n", "CAM_A, CAM_B");
	f->order = image::ChannelOrder::RGB;
	return f;
}
CFilterInvariant::Ptr populatedInvariant()
{
	auto f = CFilterInvariant::Create();
	populateCommon(*f, "_inv9", "STEREO");
	image::InvariantParams p;
	p.alpha = 0.41;
	p.beta = 0.62;
	p.order = image::ChannelOrder::RGB;
	p.linearisation = image::Linearisation::Gamma;
	p.gamma = 1.9;
	p.scale = 203.5;
	p.offset = 0.37;
	p.knee_low = 12.5;
	p.knee_high = 240.25;
	p.tail_slope_low = 0.375;
	p.tail_slope_high = 0.625;
	p.chroma_handling = image::ChromaHandling::Prefilter;
	p.chroma_sigma_px = 2.25;
	f->setParams(p);
	f->parallel_eyes = false;
	return f;
}
CFilterLinearise::Ptr populatedLinearise()
{
	auto f = CFilterLinearise::Create();
	populateCommon(*f, "_lin7", "LEFTCAM");
	f->linearisation = image::Linearisation::Gamma;
	f->gamma = 2.45;
	return f;
}

void expectSameCommon(const CObservationFilter& a, const CObservationFilter& b)
{
	EXPECT_EQ(a.common.output_suffix, b.common.output_suffix);
	EXPECT_EQ(a.common.sensor_labels, b.common.sensor_labels);
}
void expectSameMonochrome(const CFilterMonochrome& a, const CFilterMonochrome& b)
{
	expectSameCommon(a, b);
	EXPECT_EQ(a.order, b.order);
}
void expectSameInvariant(const CFilterInvariant& a, const CFilterInvariant& b)
{
	expectSameCommon(a, b);
	const auto &p = a.params(), &q = b.params();
	EXPECT_EQ(p.alpha, q.alpha);
	EXPECT_EQ(p.beta, q.beta);
	EXPECT_EQ(p.order, q.order);
	EXPECT_EQ(p.linearisation, q.linearisation);
	EXPECT_EQ(p.gamma, q.gamma);
	EXPECT_EQ(p.scale, q.scale);
	EXPECT_EQ(p.offset, q.offset);
	EXPECT_EQ(p.knee_low, q.knee_low);
	EXPECT_EQ(p.knee_high, q.knee_high);
	EXPECT_EQ(p.tail_slope_low, q.tail_slope_low);
	EXPECT_EQ(p.tail_slope_high, q.tail_slope_high);
	EXPECT_EQ(p.chroma_handling, q.chroma_handling);
	EXPECT_EQ(p.chroma_sigma_px, q.chroma_sigma_px);
	EXPECT_EQ(a.parallel_eyes, b.parallel_eyes);
}
void expectSameLinearise(const CFilterLinearise& a, const CFilterLinearise& b)
{
	expectSameCommon(a, b);
	EXPECT_EQ(a.linearisation, b.linearisation);
	EXPECT_EQ(a.gamma, b.gamma);
}

/** A keyframe map with every stored field non-default and distinct: options,
 * calibration, image size, two channels (each with its filter's class and
 * image options and its feature parameters), two runs, three keyframes (a
 * break and a second run's segment, one without ground truth), and three
 * measurements per channel and keyframe. */
CKeyframeMap::Ptr populatedKeyframeMap()
{
	auto m = CKeyframeMap::Create();
	auto& o = m->options;
	o.kf_spacing_m = 2.25;
	o.kf_spacing_deg = 12.5;
	o.landmarks_per_keyframe = 77;
	o.selection_grid_cols = 5;
	o.selection_grid_rows = 3;
	o.compression_level = 4;
	o.index_cell_m = 7.5;
	o.draw_landmarks = true;
	o.draw_landmark_max_depth_m = 22.5;
	o.draw_frame_every_m = 3.75;
	o.landmark_selection = TKeyframeMapOptions::LandmarkSelection::Strongest;
	o.reobservation_window_m = 4.5;
	o.reobservation_radius_px = 12.5;
	o.min_reobservations = 2;
	o.patch_bits = 7;
	// As maps before version 6 read (their depths were the pairs'): they load
	// to exactly this map's bytes (test_map_format.cpp, Version*MapsStillLoad).
	o.depth_from_reobservations = false;
	geometry::TStereoCalib cal;
	cal.fx = 401.5;
	cal.fy = 402.25;
	cal.cx = 255.5;
	cal.cy = 191.75;
	cal.cxR = 257.125;
	cal.baseline = 0.2375;
	map::TChannelParams a, b;
	a.label = "grey";
	a.filter_class = "shadyloc::CFilterMonochrome";
	a.filter_options = populatedMonochrome()->imageOptionsAsIni();
	a.brief_patch_size = 31;
	a.brief_seed = 0x1234567;
	a.presmooth_sigma = 0.75;
	a.sigma_px = 0.45;
	b.label = "inv9";
	b.filter_class = "shadyloc::CFilterInvariant";
	// Its images as they come (chroma_handling none, left out of the
	// options): maps of the versions before the chroma handling load to
	// exactly this map's bytes (test_map_format.cpp, Version2/3MapsStillLoad).
	auto inv = populatedInvariant();
	auto ip = inv->params();
	ip.chroma_handling = image::ChromaHandling::None;
	inv->setParams(ip);
	b.filter_options = inv->imageOptionsAsIni();
	b.brief_patch_size = 29;
	b.brief_seed = 0x7654321;
	b.presmooth_sigma = 1.25;
	b.sigma_px = 0.65;
	m->setup(cal, 500, 370, {a, b});
	const uint16_t r0 = m->addRun("dawn"), r1 = m->addRun("dusk");
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	for (int i = 0; i < 3; i++)
	{
		map::TMapKeyframe k;
		k.run = i < 2 ? r0 : r1;
		k.segment = static_cast<uint32_t>(i == 0 ? 3 : 5 + i);
		k.predicted = i > 0;
		k.frame = 1000 + 17 * i;
		k.timestamp = 1400000000.125 + 0.5 * i;
		const Eigen::AngleAxisd r(0.1 + 0.2 * i, Eigen::Vector3d(1, 2 + i, 3).normalized());
		k.T_prev_kf = Eigen::Translation3d(0.1 * i, -0.2, 1.3 + i) * r;
		T = T * k.T_prev_kf;
		k.T_map_kf = T;
		for (int x = 0; x < 6; x++)
			for (int y = x; y < 6; y++)
				k.cov_prev_kf(x, y) = k.cov_prev_kf(y, x) = (x == y ? 1e-3 : 1e-6) * (1 + x + 6 * y + 40 * i);
		if (i != 1) k.T_gt_kf = Eigen::Translation3d(5.5 + i, -2.25, 40.75) * Eigen::AngleAxisd(-0.7 + i, Eigen::Vector3d::UnitY());
		k.channels.resize(2);
		for (int c = 0; c < 2; c++)
			for (int j = 0; j < 3; j++)
			{
				features::TStereoMeasurement s;
				s.uL = 100.5f + 10 * j + 3 * c + i;
				s.v = 50.25f + 2 * j + c;
				s.uR = s.uL - (20.0625f + 7 * j + i);
				s.response = 33.0f + j + 5 * c;
				s.zncc = 0.875f - 0.01f * j;
				for (size_t w = 0; w < s.desc.w.size(); w++)
					s.desc.w[w] = 0x0123456789abcdefull * (w + 1) + static_cast<uint64_t>(j + 3 * c + 9 * i);
				for (size_t p = 0; p < s.patch.size(); p++) s.patch[p] = static_cast<uint8_t>(3 * p + 11 * j + 5 * c + i);
				k.channels[c].push_back(s);
			}
		m->appendKeyframe(std::move(k));
	}
	return m;
}

void expectSameKeyframeMap(const CKeyframeMap& a, const CKeyframeMap& b)
{
	EXPECT_TRUE(a.options == b.options);
	const auto &ca = a.calibration(), &cb = b.calibration();
	EXPECT_EQ(ca.fx, cb.fx);
	EXPECT_EQ(ca.fy, cb.fy);
	EXPECT_EQ(ca.cx, cb.cx);
	EXPECT_EQ(ca.cy, cb.cy);
	EXPECT_EQ(ca.cxR, cb.cxR);
	EXPECT_EQ(ca.baseline, cb.baseline);
	EXPECT_EQ(a.imageWidth(), b.imageWidth());
	EXPECT_EQ(a.imageHeight(), b.imageHeight());
	EXPECT_EQ(a.channels(), b.channels());
	EXPECT_EQ(a.runs(), b.runs());
	ASSERT_EQ(a.keyframeCount(), b.keyframeCount());
	for (uint32_t i = 0; i < a.keyframeCount(); i++)
	{
		SCOPED_TRACE("keyframe " + std::to_string(i));
		const auto &x = a.keyframe(i), &y = b.keyframe(i);
		EXPECT_EQ(x.id, y.id);
		EXPECT_EQ(x.run, y.run);
		EXPECT_EQ(x.segment, y.segment);
		EXPECT_EQ(x.frame, y.frame);
		EXPECT_EQ(x.timestamp, y.timestamp);
		EXPECT_EQ(x.predicted, y.predicted);
		EXPECT_EQ(x.T_map_kf.matrix(), y.T_map_kf.matrix());
		EXPECT_EQ(x.T_prev_kf.matrix(), y.T_prev_kf.matrix());
		EXPECT_EQ(x.cov_prev_kf, y.cov_prev_kf);
		ASSERT_EQ(bool(x.T_gt_kf), bool(y.T_gt_kf));
		if (x.T_gt_kf)
		{
			EXPECT_EQ(x.T_gt_kf->matrix(), y.T_gt_kf->matrix());
		}
		ASSERT_EQ(x.channels.size(), y.channels.size());
		for (size_t c = 0; c < x.channels.size(); c++)
		{
			ASSERT_EQ(x.channels[c].size(), y.channels[c].size()) << "channel " << c;
			for (size_t j = 0; j < x.channels[c].size(); j++)
			{
				const auto &p = x.channels[c][j], &q = y.channels[c][j];
				EXPECT_EQ(p.uL, q.uL);
				EXPECT_EQ(p.v, q.v);
				EXPECT_EQ(p.uR, q.uR);
				EXPECT_EQ(p.sigma_d, q.sigma_d);
				EXPECT_EQ(p.response, q.response);
				EXPECT_EQ(p.zncc, q.zncc);
				EXPECT_TRUE(p.desc == q.desc);
				EXPECT_EQ(p.patch, q.patch);
				EXPECT_EQ(p.P, q.P);
				EXPECT_EQ(p.cov, q.cov);
			}
		}
	}
}

/** Every shadyloc:: class the registry must hold, and how to test it. A class
 * registered but missing here (or listed but not registered) fails
 * FormatsRegistry.EveryClassIsListedAndRoundTrips: a new class needs its
 * populated instance, its field comparison and a golden file. */
struct TClassCase
{
	bool abstract = false;
	std::function<mrpt::serialization::CSerializable::Ptr()> populated;
	std::function<void(const mrpt::serialization::CSerializable&, const mrpt::serialization::CSerializable&)> expectSame;
};

template <class T>
TClassCase concrete(std::function<typename T::Ptr()> make, void (*same)(const T&, const T&))
{
	TClassCase c;
	c.populated = [make] { return make(); };
	c.expectSame = [same](const mrpt::serialization::CSerializable& a, const mrpt::serialization::CSerializable& b) {
		const auto* x = dynamic_cast<const T*>(&a);
		const auto* y = dynamic_cast<const T*>(&b);
		ASSERT_TRUE(x && y) << "wrong class read back";
		same(*x, *y);
	};
	return c;
}

const std::map<std::string, TClassCase>& classCases()
{
	static const std::map<std::string, TClassCase> cases = [] {
		std::map<std::string, TClassCase> m;
		m["shadyloc::CObservationFilter"].abstract = true;
		m["shadyloc::CFilterMonochrome"] = concrete<CFilterMonochrome>(populatedMonochrome, expectSameMonochrome);
		m["shadyloc::CFilterInvariant"] = concrete<CFilterInvariant>(populatedInvariant, expectSameInvariant);
		m["shadyloc::CFilterLinearise"] = concrete<CFilterLinearise>(populatedLinearise, expectSameLinearise);
		m["shadyloc::CKeyframeMap"] = concrete<CKeyframeMap>(populatedKeyframeMap, expectSameKeyframeMap);
		return m;
	}();
	return cases;
}

std::set<std::string> registeredShadylocClasses()
{
	registerAllClasses();
	std::set<std::string> out;
	for (const auto* c : mrpt::rtti::getAllRegisteredClasses())
		if (std::string(c->className).rfind("shadyloc::", 0) == 0) out.insert(c->className);
	return out;
}

std::string goldenName(const std::string& className)
{
	return className.substr(std::string("shadyloc::").size()) + ".bin";
}

/** The three populated filters as the pipeline the filter record is made of. */
filters::FilterPipeline populatedPipeline()
{
	filters::FilterPipeline p;
	p.filters = {populatedMonochrome(), populatedInvariant(), populatedLinearise()};
	return p;
}

/** The record `shadyloc filter` writes as the first object of its output, for
 * the populated pipeline, taken from a real run of the processor. */
std::string filterRecordText(mrpt::obs::CObservationComment::Ptr* recordOut = nullptr)
{
	const std::string dir = test::tempDir("formats_record");
	{
		// One synthetic frame per camera the populated filters name (a filter
		// whose sensor_labels match no observation is an error).
		io::RawlogWriter w(dir + "/in.rawlog");
		for (const char* label : {"CAM_A", "STEREO", "LEFTCAM"})
		{
			auto obs = test::syntheticStereoFrame(0);
			obs->sensorLabel = label;
			w.write(*obs);
		}
		w.commit();
	}
	filters::RawlogFilterProcessor proc;
	proc.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	proc.run(dir + "/in.rawlog", dir + "/out.rawlog", populatedPipeline());
	io::RawlogReader r(dir + "/out.rawlog");
	auto first = r.next();
	const auto obs = io::observationsIn(first);
	EXPECT_EQ(obs.size(), 1u);
	auto c = obs.empty() ? nullptr : std::dynamic_pointer_cast<mrpt::obs::CObservationComment>(obs[0]);
	if (!c) throw std::runtime_error("the filter output does not start with its record");
	if (recordOut) *recordOut = c;
	return c->text;
}

/** Compares `actual` with the golden file, or rewrites it when asked. */
void checkGolden(const std::string& name, const Bytes& actual)
{
	const std::string path = kGoldenDir + "/" + name;
	if (test::updatingGolden())
	{
		writeGoldenFile(path, actual);
		ADD_FAILURE() << "rewrote " << path
					  << " (SHADYLOC_UPDATE_GOLDEN is set): review `git diff tests/golden`, "
						 "then run again without it";
		return;
	}
	const Bytes golden = test::fileBytes(path);
	ASSERT_FALSE(golden.empty()) << "golden file " << path << " is missing or empty";
	if (golden == actual) return;
	size_t at = 0;
	while (at < golden.size() && at < actual.size() && golden[at] == actual[at]) at++;
	ADD_FAILURE() << name << ": bytes differ from the golden file from byte " << at << " (golden "
				  << golden.size() << " bytes, now " << actual.size()
				  << "). A field added, removed or reordered in the writer: bump the format "
					 "version, keep reading the old one where files exist, and regenerate "
					 "(see the top of tests/unit/test_formats.cpp).";
}
}  // namespace

// ---- the registry: every class listed, each round-trips to identical bytes --

// Each class registers itself when the library loads, in the file that
// defines its class id (src/Registration.cpp says why): a program that calls
// nothing (this test, alone in its process under ctest) finds every class by
// name. Under clang this failed while the list in another file did it.
TEST(FormatsRegistry, ClassesAreRegisteredWhenTheLibraryLoads)
{
	for (const char* name :
		 {"shadyloc::CObservationFilter", "shadyloc::CFilterMonochrome", "shadyloc::CFilterInvariant",
		  "shadyloc::CFilterLinearise", "shadyloc::CKeyframeMap"})
	{
		const auto* id = mrpt::rtti::findRegisteredClass(name);
		ASSERT_NE(id, nullptr) << name << " is not registered at load time";
		EXPECT_STREQ(id->className, name);
	}
	EXPECT_NE(mrpt::rtti::classFactory("shadyloc::CFilterInvariant"), nullptr);
}

TEST(FormatsRegistry, EveryClassIsListedAndRoundTrips)
{
	const auto registered = registeredShadylocClasses();
	ASSERT_FALSE(registered.empty()) << "no shadyloc:: class registered";
	for (const auto& name : registered)
		EXPECT_TRUE(classCases().count(name))
			<< name << " is registered but not covered: add it to classCases() in " << __FILE__
			<< " (a populated instance, a field comparison) and a golden file";
	for (const auto& [name, c] : classCases())
		EXPECT_TRUE(registered.count(name)) << name << " is listed but not registered (src/Registration.cpp)";

	for (const auto& name : registered)
	{
		if (!classCases().count(name)) continue;
		SCOPED_TRACE(name);
		const auto& c = classCases().at(name);
		const auto* id = mrpt::rtti::findRegisteredClass(name);
		ASSERT_NE(id, nullptr);
		if (c.abstract)
		{
			EXPECT_EQ(id->createObject(), nullptr) << "listed as abstract but creatable";
			continue;
		}
		// Creatable by name, as a reader of a file does it.
		const auto fresh = std::dynamic_pointer_cast<mrpt::serialization::CSerializable>(
			mrpt::rtti::classFactory(name));
		ASSERT_TRUE(fresh) << "not creatable by name";
		const auto obj = c.populated();
		ASSERT_EQ(std::string(obj->GetRuntimeClass()->className), name);
		const Bytes first = serialise(*obj);
		EXPECT_NE(first, serialise(*fresh)) << "the populated instance serialises like a default one";
		const auto back = deserialise(first);
		ASSERT_TRUE(back);
		EXPECT_EQ(std::string(back->GetRuntimeClass()->className), name);
		c.expectSame(*obj, *back);
		EXPECT_EQ(serialise(*back), first) << "write -> read -> write changed the bytes";
		// A default-constructed instance round-trips too.
		EXPECT_EQ(serialise(*deserialise(serialise(*fresh))), serialise(*fresh));
	}
}

// ---- golden files ----------------------------------------------------------

TEST(FormatsGolden, RegisteredClassesMatchTheirGoldenFiles)
{
	for (const auto& [name, c] : classCases())
	{
		if (c.abstract) continue;
		SCOPED_TRACE(name);
		const auto obj = c.populated();
		checkGolden(goldenName(name), serialise(*obj));
		if (test::updatingGolden()) continue;
		// The golden bytes load into the same fields.
		const auto back = deserialise(test::fileBytes(kGoldenDir + "/" + goldenName(name)));
		ASSERT_TRUE(back);
		c.expectSame(*obj, *back);
	}
}

// CFilterInvariant version 0 (before compressed tails; the golden file as it
// was) still loads, as the linear mapping it described.
TEST(FormatsGolden, InvariantFilterVersion0StillLoads)
{
	const auto back = deserialise(test::fileBytes(kGoldenDir + "/CFilterInvariant_v0.bin"));
	ASSERT_TRUE(back);
	const auto* f = dynamic_cast<const CFilterInvariant*>(back.get());
	ASSERT_NE(f, nullptr);
	auto expected = populatedInvariant()->params();
	expected.knee_low = 0;
	expected.knee_high = 255;
	expected.tail_slope_low = expected.tail_slope_high = 1;
	expected.chroma_handling = image::ChromaHandling::None;
	EXPECT_TRUE(f->params().sameImageAs(expected)) << f->params().asString();
	EXPECT_FALSE(f->params().hasCompressedTails());
	EXPECT_EQ(f->common.output_suffix, "_inv9");
}

// CFilterInvariant version 1 (before the chroma handling; the golden file as
// it was) still loads, with every pixel as it comes.
TEST(FormatsGolden, InvariantFilterVersion1StillLoads)
{
	const auto back = deserialise(test::fileBytes(kGoldenDir + "/CFilterInvariant_v1.bin"));
	ASSERT_TRUE(back);
	const auto* f = dynamic_cast<const CFilterInvariant*>(back.get());
	ASSERT_NE(f, nullptr);
	auto expected = populatedInvariant()->params();
	expected.chroma_handling = image::ChromaHandling::None;
	EXPECT_TRUE(f->params().sameImageAs(expected)) << f->params().asString();
	EXPECT_TRUE(f->params().hasCompressedTails());
	EXPECT_EQ(f->common.output_suffix, "_inv9");
}

TEST(FormatsGolden, FilterRecordMatchesItsGoldenFile)
{
	mrpt::obs::CObservationComment::Ptr record;
	const std::string text = filterRecordText(&record);
	EXPECT_EQ(text.rfind(filters::kRecordHeader, 0), 0u) << text;
	checkGolden("filter_record.txt", asBytes(text));
	if (test::updatingGolden()) return;
	// The golden record builds the same filters.
	const Bytes g = test::fileBytes(kGoldenDir + "/filter_record.txt");
	const std::string golden(g.begin(), g.end());
	mrpt::config::CConfigFileMemory cfg(golden.substr(std::string(filters::kRecordHeader).size() + 1));
	const auto p = filters::FilterPipeline::FromConfig(cfg, "tests/golden/filter_record.txt");
	const auto want = populatedPipeline();
	ASSERT_EQ(p.filters.size(), want.filters.size());
	for (size_t i = 0; i < p.filters.size(); i++)
	{
		const std::string name = want.filters[i]->GetRuntimeClass()->className;
		SCOPED_TRACE(name);
		ASSERT_EQ(std::string(p.filters[i]->GetRuntimeClass()->className), name);
		classCases().at(name).expectSame(*want.filters[i], *p.filters[i]);
	}
}

// ---- bounded reads ---------------------------------------------------------

namespace
{
bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

void putU32(Bytes& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }
}  // namespace

TEST(FormatsBoundedRead, FilterStringLengthAndEnumsAreChecked)
{
	// The first string length of the object data follows the class name and
	// version byte; find it as the length of the known suffix.
	const auto f = populatedMonochrome();
	const Bytes good = serialise(*f);
	const uint32_t len = static_cast<uint32_t>(f->common.output_suffix.size());
	size_t at = 0;
	for (; at + 8 < good.size(); at++)
		if (std::memcmp(good.data() + at, &len, 4) == 0 &&
			std::memcmp(good.data() + at + 4, f->common.output_suffix.data(), len) == 0)
			break;
	ASSERT_LT(at + 8, good.size());
	Bytes bad = good;
	putU32(bad, at, 0xFFFFFFF0u);
	const std::string e = test::errorOf([&] { deserialise(bad); });
	EXPECT_TRUE(has(e, "shadyloc::CFilterMonochrome (version 0): byte 0: output_suffix: count 4294967280 exceeds"))
		<< e;
	// The channel order is the last data byte before MRPT's end marker.
	bad = good;
	const size_t orderAt = at + 4 + len + 4 + f->common.sensor_labels.size();
	ASSERT_EQ(bad[orderAt], static_cast<uint8_t>(image::ChannelOrder::RGB));
	bad[orderAt] = 9;
	const std::string e2 = test::errorOf([&] { deserialise(bad); });
	EXPECT_TRUE(has(e2, "channel_order: value 9 out of range")) << e2;
}

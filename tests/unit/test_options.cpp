/* ShadyLoc tests: the one options idiom (core/Options.h). Every options
 * struct declares its keys once; for each of them a dump loads back to the
 * same values (defaults, and every key changed in turn), and the docs'
 * options tables are the ones its declaration generates.
 *
 * SHADYLOC_WRITE_DOCS=1 rewrites the docs' tables instead of comparing them. */
#include "../support/TestSupport.h"

#include <shadyloc/core/Options.h>
#include <shadyloc/datasets/Common.h>
#include <shadyloc/datasets/Folder.h>
#include <shadyloc/datasets/Kitti.h>
#include <shadyloc/features/StereoFeatures.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/ColourTransforms.h>
#include <shadyloc/localisation/LocalisationSystem.h>
#include <shadyloc/Localiser.h>
#include <shadyloc/localisation/LocaliserAppKeys.h>
#include <shadyloc/localisation/MonocularLocaliser.h>
#include <shadyloc/localisation/StereoLocaliser.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/vo/StereoVO.h>

#include <gtest/gtest.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace shadyloc;
using core::Range;

namespace
{
// ---- the idiom itself ----------------------------------------------------------------
struct TExample
{
	enum class Mode
	{
		Fast,
		Exact
	};
	double radius = 2.5;
	int count = 3;
	bool on = true;
	Mode mode = Mode::Exact;
	std::string name = "a";
	core::Words list = {"x", "y"};

	void keys(core::KeyVisitor& v)
	{
		v.renamed({{"radius", "radius_px"}});
		v("radius_px", radius, "px", Range::above(0), "search window");
		v("count", count, "", Range::closed(1, 10).orOff(), "");
		v("on", on, "", Range::any(), "switch | flag");
		v.choice("mode", mode, {{"fast", Mode::Fast}, {"exact", Mode::Exact}}, "");
		v("name", name, "", Range::any(), "");
		v("list", list, "", Range::any(), "names");
	}
	void validate() const { core::checkKeys(*this); }
};

std::string dumped(const TExample& o)
{
	std::ostringstream s;
	core::dumpKeys(o, s);
	return s.str();
}

TExample loaded(const std::string& text)
{
	mrpt::config::CConfigFileMemory c(text);
	TExample o;
	core::loadKeys(o, c, "ex");
	return o;
}

std::string messageOf(const std::function<void()>& f)
{
	try
	{
		f();
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "(no error)";
}
}  // namespace

TEST(Options, RangeTextIsTheErrorAndTheDocsColumn)
{
	EXPECT_EQ(Range::atLeast(0).text(), ">= 0");
	EXPECT_EQ(Range::above(0.5).text(), "> 0.5");
	EXPECT_EQ(Range::openClosed(0, 1).text(), "in (0, 1]");
	EXPECT_EQ(Range::closedOpen(-1, 1e6).text(), "in [-1, 1e+06)");
	EXPECT_EQ(Range::closed(2, 1000).orOff().text(), "0 (off) or in [2, 1000]");
	EXPECT_EQ(Range::any().text(), "");
	EXPECT_TRUE(Range::closed(2, 1000).orOff().contains(0));
	EXPECT_FALSE(Range::closed(2, 1000).orOff().contains(1));
	EXPECT_FALSE(Range::openClosed(0, 1).contains(0));
	EXPECT_TRUE(Range::openClosed(0, 1).contains(1));
	EXPECT_FALSE(Range::atLeast(0).contains(std::nan("")));
}

TEST(Options, OneDeclarationDrivesLoadDumpAndChecks)
{
	const TExample d;
	EXPECT_EQ(dumped(d),
			  "; search window [px]\nradius_px = 2.5\ncount = 3\n; switch | flag\non = true\nmode = exact\nname = a\n"
			  "; names\nlist = x y\n");
	const TExample o = loaded("[ex]\nradius_px = 0.25 ; r\ncount = 0\non = no\nmode = FAST\nname = b\nlist = p, q\tr\n");
	EXPECT_EQ(o.radius, 0.25);
	EXPECT_EQ(o.count, 0);
	EXPECT_FALSE(o.on);
	EXPECT_TRUE(o.mode == TExample::Mode::Fast);
	EXPECT_EQ(o.name, "b");
	EXPECT_EQ(o.list, (core::Words{"p", "q", "r"}));
	EXPECT_EQ(dumped(loaded("[ex]\n" + dumped(o))), dumped(o));

	// All of the strict reader's refusals, and the ranges, name section and key.
	EXPECT_EQ(messageOf([] { loaded("[ex]\nradius = 1\n"); }),
			  "[ex] radius: this key was renamed to 'radius_px' (same meaning and unit); rename it");
	EXPECT_EQ(messageOf([] { loaded("[ex]\ncuont = 1\n"); }), "[ex] cuont: unknown key; did you mean 'count'?");
	EXPECT_EQ(messageOf([] { loaded("[ex]\ncount = 11\n"); }), "[ex] count: must be 0 (off) or in [1, 10]");
	EXPECT_EQ(messageOf([] { loaded("[ex]\nradius_px = 0\n"); }), "[ex] radius_px: must be > 0");
	EXPECT_EQ(messageOf([] { loaded("[ex]\nmode = slow\n"); }), "[ex] mode: 'slow' is not one of: fast | exact");

	// Values set in code are checked by the same declaration.
	TExample bad;
	bad.radius = std::nan("");
	EXPECT_EQ(messageOf([&] { bad.validate(); }), "radius_px: must be a finite number");
	bad = TExample();
	bad.mode = static_cast<TExample::Mode>(7);
	EXPECT_EQ(messageOf([&] { bad.validate(); }), "mode: must be one of: fast, exact");
}

TEST(Options, TableOfTheDocs)
{
	EXPECT_EQ(core::keyTable(TExample()),
			  "| key | default | unit | range | meaning |\n|---|---|---|---|---|\n"
			  "| `radius_px` | `2.5` | px | > 0 | search window |\n"
			  "| `count` | `3` | - | 0 (off) or in [1, 10] |  |\n"
			  "| `on` | `true` | - | - | switch \\| flag |\n"
			  "| `mode` | `exact` | - | `fast`, `exact` |  |\n"
			  "| `name` | `a` | - | - |  |\n"
			  "| `list` | `x y` | - | - | names |\n");
}

// ---- every options struct -------------------------------------------------------------
namespace
{
/** Changes the key at `target` to its `choice`-th alternative; `changed`
 * says whether there was one. */
class Perturber : public core::KeyVisitor
{
   public:
	Perturber(size_t target, size_t choice) : m_target(target), m_choice(choice) {}
	size_t count = 0;
	bool changed = false;
	bool unwritten = false;	 //!< the target is not in the dump (or not changeable alone): skipped
	std::string name;  //!< of the target key

   protected:
	void key(const core::KeyDef& k, Field v) override
	{
		if (count++ != m_target) return;
		name = k.name;
		unwritten = !k.written;
		if (unwritten) return;	// not in this dump: nothing to load back
		std::visit([&](auto* p) { changed = alternative(*p, k.range); }, v);
	}
	void choiceKey(const core::KeyDef& k, std::string& v, const std::vector<std::string>& names) override
	{
		if (count++ != m_target) return;
		name = k.name;
		size_t at = 0;
		while (at < names.size() && names[at] != v) at++;
		if (m_choice + 1 >= names.size()) return;
		v = names[(at + 1 + m_choice) % names.size()];
		changed = true;
	}
	void textKey(const core::KeyDef& k, std::string&, const std::function<void(const std::string&)>& set) override
	{
		if (count++ != m_target) return;
		name = k.name;
		// [sim] traversals names sections: the whole file's round trip covers it.
		unwritten = name == "traversals";
		// A text key's format is its own: a sample per key.
		if (m_choice > 0 || name != "markers") return;
		set("1 2 3 0.5, -4 5.5 1e-3 2");
		changed = true;
	}

   private:
	bool alternative(bool& b, const Range&)
	{
		if (m_choice > 0) return false;
		b = !b;
		return true;
	}
	bool alternative(std::string& s, const Range&)
	{
		if (m_choice > 0) return false;
		s = s.empty() ? "CAM" : s + "x";
		return true;
	}
	bool alternative(core::Words& w, const Range&)
	{
		// One more word, then two (a list that needs two or none).
		if (m_choice > 1) return false;
		w.push_back("extra");
		if (m_choice == 1) w.push_back("extra2");
		return true;
	}
	template <typename T>
	bool alternative(T& x, const Range& r)
	{
		// Small steps first (they keep one key's order against another).
		const double step = std::is_integral_v<T> ? 1.0 : 0.25;
		const double d = static_cast<double>(x);
		const double cands[] = {d + step, d - step, d + 2 * step, d * 2, 0, 1, 2, 4, 8, 10};
		size_t seen = 0;
		for (double c : cands)
		{
			if (std::is_unsigned_v<T> && c < 0) continue;
			const T t = static_cast<T>(c);
			if (static_cast<double>(t) != c || t == x || !r.contains(c)) continue;
			if (seen++ == m_choice)
			{
				x = t;
				return true;
			}
		}
		return false;
	}

	size_t m_target, m_choice;
};

/** One options struct as the test sees it. */
struct TOptionsCase
{
	std::string name;  //!< the docs' table name
	std::function<std::string()> table;
	std::function<void()> roundTrip;
	bool documented = true;	 //!< has a table in docs/
};

template <typename T, typename Load, typename Dump>
void expectRoundTrips(const std::string& section, Load load, Dump dump, const std::function<T()>& make)
{
	auto text = [&](const T& o) {
		std::ostringstream s;
		dump(o, s);
		return s.str();
	};
	auto fromText = [&](const std::string& t, T o) {
		// A dump that writes its section header (the simulator's) is a whole file.
		mrpt::config::CConfigFileMemory c(t.rfind("[", 0) == 0 ? t : "[" + section + "]\n" + t);
		load(o, c, section);
		return o;
	};
	const std::string defaults = text(make());
	EXPECT_EQ(text(fromText(defaults, T())), defaults) << "defaults";

	// Each key in turn set to another valid value: the dump says so, loads
	// back to it, and a dump of the defaults loaded over it restores them.
	size_t keys = 0;
	{
		Perturber counter(size_t(-1), 0);
		T o = make();
		o.keys(counter);
		keys = counter.count;
	}
	ASSERT_GT(keys, 0u);
	for (size_t i = 0; i < keys; i++)
	{
		std::string key;
		bool done = false;
		for (size_t choice = 0; !done; choice++)
		{
			T o = make();
			Perturber p(i, choice);
			o.keys(p);
			key = p.name;
			if (p.unwritten) done = true;
			if (!p.changed) break;
			try
			{
				o.validate();
			}
			catch (const std::invalid_argument&)
			{
				continue;  // against another key's value: try the next alternative
			}
			const std::string changed = text(o);
			EXPECT_NE(changed, defaults) << section << " " << key;
			EXPECT_EQ(text(fromText(changed, T())), changed) << section << " " << key;
			EXPECT_EQ(text(fromText(defaults, o)), defaults) << section << " " << key;
			done = true;
		}
		EXPECT_TRUE(done) << "[" << section << "] " << key << ": no other valid value found to test";
	}
}

/** make: the values to start from (the defaults unless given). */
template <typename T, typename Load, typename Dump>
TOptionsCase optionsCase(
	const std::string& name, const std::string& section, Load load, Dump dump, std::function<T()> make = [] { return T(); })
{
	return {name, [make] { return core::keyTable(make()); },
			[=] { expectRoundTrips<T>(section, load, dump, make); }};
}

/** LocaliserOptions' own keys, owning its options. */
struct TAppKeys
{
	LocaliserOptions o;
	void keys(core::KeyVisitor& v) { localisation::TLocaliserAppKeys{o.sensor_label, o.start_keyframe}.keys(v); }
	void validate() const { core::checkKeys(*this); }
};

template <typename T>
void loadCL(T& o, const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	o.loadFromConfigFile(c, s);
}
template <typename T>
void dumpCL(const T& o, std::ostream& out)
{
	o.dumpToTextStream(out);
}
template <typename T>
void loadPlain(T& o, const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	o.load(c, s);
}
template <typename T>
void dumpPlain(const T& o, std::ostream& out)
{
	o.dump(out);
}
template <typename T>
void loadGeneric(T& o, const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(o, c, s);
}
template <typename T>
void dumpGeneric(const T& o, std::ostream& out)
{
	core::dumpKeys(o, out);
}

/** TSimOptions as the round trip sees it: config/sim.ini. */
struct TSimFile : sim::TSimOptions
{
	void validate() const {}  // each section's load validates it
};
TSimFile simFile()
{
	TSimFile f;
	static_cast<sim::TSimOptions&>(f) = sim::TSimOptions::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/sim.ini");
	return f;
}

/** A filter's section as FilterPipeline reads and asIni() writes it: class,
 * the common keys, its own keys (those the round trip changes). */
template <typename T>
void loadFilter(T& f, const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	f.loadFromConfig(c, s);
}
template <typename T>
void dumpFilter(const T& f, std::ostream& out)
{
	out << f.optionsAsIni();
}
template <typename T>
TOptionsCase filterCase(const std::string& name, const std::string& section)
{
	return optionsCase<T>(name, section, loadFilter<T>, dumpFilter<T>);
}

/** The keys every filter has: their table shows no default suffix (each class has its own). */
TOptionsCase filterCommonCase()
{
	using TCommon = CObservationFilter::TCommonOptions;
	TOptionsCase c = optionsCase<TCommon>(
		"filter", "filter", loadGeneric<TCommon>, dumpGeneric<TCommon>, std::function<TCommon()>([] {
			TCommon o;
			o.output_suffix = "_mono";
			return o;
		}));
	c.table = [] { return core::keyTable(TCommon()); };
	return c;
}

/** The folder calibration (a file of three sections) through its own load
 * and dump, one section's keys changed: a camera's ([left]; [right] has the
 * same declaration) or [stereo]'s. */
template <bool Stereo>
struct TCalibSection
{
	datasets::TFolderCalib c;
	void keys(core::KeyVisitor& v)
	{
		if constexpr (Stereo)
			c.stereoKeys().keys(v);
		else
			c.leftKeys().keys(v);
	}
	void validate() const { core::checkKeys(*this); }
};
template <bool Stereo>
TOptionsCase calibCase(const std::string& name)
{
	using T = TCalibSection<Stereo>;
	return optionsCase<T>(
		name, "calib", [](T& o, const mrpt::config::CConfigFileBase& c, const std::string& s) { o.c.loadFromConfigFile(c, s); },
		[](const T& o, std::ostream& out) { o.c.dumpToTextStream(out); }, std::function<T()>([] {
			T o;
			o.c = datasets::TFolderCalib::FromFile(std::string(SHADYLOC_SOURCE_DIR) + "/config/folder_calib_example.ini");
			return o;
		}));
}

TOptionsCase undocumented(TOptionsCase c)
{
	c.documented = false;
	return c;
}

/** Every options struct of the library, by the name of its docs table. */
const std::vector<TOptionsCase>& optionsCases()
{
	static const std::vector<TOptionsCase> cases = {
		optionsCase<TKeyframeMapOptions>("map", "map", loadCL<TKeyframeMapOptions>, dumpCL<TKeyframeMapOptions>),
		optionsCase<features::TStereoFeatureOptions>(
			"features", "features", loadCL<features::TStereoFeatureOptions>, dumpCL<features::TStereoFeatureOptions>),
		optionsCase<vo::TStereoVOOptions>("vo", "vo", loadCL<vo::TStereoVOOptions>, dumpCL<vo::TStereoVOOptions>),
		optionsCase<localisation::TLocaliserOptions>(
			"localiser", "localiser", loadPlain<localisation::TLocaliserOptions>,
			dumpPlain<localisation::TLocaliserOptions>),
		optionsCase<localisation::TMonocularLocaliserOptions>(
			"localiser_2d", "localiser_2d", loadPlain<localisation::TMonocularLocaliserOptions>,
			dumpPlain<localisation::TMonocularLocaliserOptions>),
		optionsCase<localisation::TSystemOptions>(
			"localise", "localise", loadPlain<localisation::TSystemOptions>, dumpPlain<localisation::TSystemOptions>),
		optionsCase<TAppKeys>("application", "application", loadGeneric<TAppKeys>, dumpGeneric<TAppKeys>),
		optionsCase<image::InvariantParams>(
			"invariant", "invariant", loadCL<image::InvariantParams>, dumpCL<image::InvariantParams>),
		optionsCase<datasets::TImportOptions>(
			"import", "import", loadCL<datasets::TImportOptions>, dumpCL<datasets::TImportOptions>),
		optionsCase<datasets::KittiExporter::TOptions>(
			"export_kitti", "export", loadCL<datasets::KittiExporter::TOptions>,
			dumpCL<datasets::KittiExporter::TOptions>),
		optionsCase<sim::TSimCameraOptions>(
			"sim.camera", "sim.camera", loadCL<sim::TSimCameraOptions>, dumpCL<sim::TSimCameraOptions>),
		optionsCase<sim::TSimSceneOptions>(
			"sim.scene", "sim.scene", loadCL<sim::TSimSceneOptions>, dumpCL<sim::TSimSceneOptions>),
		optionsCase<sim::TTraversal>("traversal", "traversal.", loadCL<sim::TTraversal>, dumpCL<sim::TTraversal>),
		// The other of a traversal's alternative keys: an end instead of a count (no table of its own).
		undocumented(optionsCase<sim::TTraversal>(
			"traversal_to_end", "traversal.", loadCL<sim::TTraversal>, dumpCL<sim::TTraversal>,
			std::function<sim::TTraversal()>([] {
				sim::TTraversal t;
				t.frames = 0;
				t.end_s_m = 120;
				return t;
			}))),
		filterCommonCase(),
		filterCase<CFilterMonochrome>("CFilterMonochrome", "mono"),
		filterCase<CFilterInvariant>("CFilterInvariant", "invariant"),
		filterCase<CFilterLinearise>("CFilterLinearise", "lin"),
		calibCase<false>("folder_calib.camera"),
		calibCase<true>("folder_calib.stereo"),
		// The whole simulator file: [sim] names the traversals, each read from its section.
		optionsCase<TSimFile>("sim", "sim", loadCL<TSimFile>, dumpCL<TSimFile>, std::function<TSimFile()>(simFile)),
	};

	return cases;
}
}  // namespace

TEST(Options, EveryStructsDumpLoadsBackToTheSameValues)
{
	for (const auto& c : optionsCases())
	{
		SCOPED_TRACE(c.name);
		c.roundTrip();
	}
}

// Guards the list above: a struct that declares keys but is not in it fails.
TEST(Options, EveryStructDeclaringKeysIsTested)
{
	size_t declared = 0;
	for (const auto& e : std::filesystem::recursive_directory_iterator(std::string(SHADYLOC_SOURCE_DIR) + "/include"))
	{
		const std::string t = test::fileContents(e.path().string());
		for (size_t at = t.find("void keys(core::KeyVisitor& v)"); at != std::string::npos;
			 at = t.find("void keys(core::KeyVisitor& v)", at + 1))
			declared++;
	}
	// One documented case per struct (TLocaliserAppKeys, the public face's
	// keys, is tested as TAppKeys).
	EXPECT_EQ(declared, std::count_if(optionsCases().begin(), optionsCases().end(),
									  [](const TOptionsCase& c) { return c.documented; }));
}

// The docs' options tables are generated from the declarations: a table
// between "<!-- options-table: NAME -->" and "<!-- /options-table -->" must be
// NAME's keyTable(); every struct has one.
TEST(Options, DocsTablesAreTheDeclarations)
{
	const bool write = std::getenv("SHADYLOC_WRITE_DOCS") != nullptr;
	const std::string open = "<!-- options-table: ", close = "<!-- /options-table -->";
	std::set<std::string> documented;
	for (const auto& e : std::filesystem::directory_iterator(std::string(SHADYLOC_SOURCE_DIR) + "/docs"))
	{
		if (e.path().extension() != ".md") continue;
		const std::string text = test::fileContents(e.path().string());
		std::string out;
		size_t from = 0;
		for (size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1))
		{
			const size_t nameEnd = text.find(" -->\n", at);
			const size_t end = text.find(close, at);
			ASSERT_TRUE(nameEnd != std::string::npos && end != std::string::npos && nameEnd < end)
				<< e.path() << ": an options-table block without its end";
			const std::string name = text.substr(at + open.size(), nameEnd - at - open.size());
			const size_t body = nameEnd + 5;
			auto c = std::find_if(optionsCases().begin(), optionsCases().end(),
								  [&](const TOptionsCase& x) { return x.name == name; });
			if (c == optionsCases().end())
			{
				ADD_FAILURE() << e.path() << ": no options struct named '" << name << "'";
				continue;
			}
			documented.insert(name);
			const std::string table = c->table();
			if (!write)
			{
				EXPECT_EQ(text.substr(body, end - body), table)
					<< e.path() << ": the table '" << name << "' differs from its declaration "
					<< "(SHADYLOC_WRITE_DOCS=1 shadyloc_tests --gtest_filter=Options.DocsTables* rewrites it)";
			}
			out += text.substr(from, body - from) + table;
			from = end;
		}
		out += text.substr(from);
		if (write && out != text) std::ofstream(e.path()) << out;
	}
	for (const auto& c : optionsCases())
		if (c.documented)
		{
			EXPECT_TRUE(documented.count(c.name)) << "no docs table for '" << c.name << "'";
		}
}

// [localise] seed_with_places became each localiser's place_seeds_search
// (twenty-second session): a config that still sets it is refused, naming
// where the key lives now.
TEST(Options, AMovedKeyIsRefusedNamingItsNewSection)
{
	mrpt::config::CConfigFileMemory c("[localise]\nseed_with_places = true\n");
	localisation::TSystemOptions o;
	EXPECT_EQ(messageOf([&] { o.load(c, "localise"); }),
			  "[localise] seed_with_places: this key moved to 'place_seeds_search' in [localiser] or "
			  "[localiser.<channel>]; move it there");
}

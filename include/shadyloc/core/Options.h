/* ShadyLoc — one declaration per settings key drives load, dump, validation
 * and the docs' options tables.
 *
 * An options struct lists its keys once, in the order of its canonical dump:
 *
 *   void TFoo::keys(core::KeyVisitor& v)
 *   {
 *       v.renamed({{"radius", "radius_px"}});             // before the keys
 *       v("radius_px", radius, "px", Range::above(0), "search window");
 *       v.choice("mode", mode, {{"fast", Mode::Fast}, {"exact", Mode::Exact}}, "fast | exact");
 *   }
 *
 * (key, field, unit, range, comment). The visitors do the rest:
 *   readKeys / loadKeys - through SettingsSection, with all its strictness;
 *     loadKeys then calls validate(), errors naming file, section and key;
 *   writeKeys / dumpKeys - through SettingsWriter: "comment [unit]" on its own
 *     line before "key = value", which loads back to the same values;
 *   checkKeys - the ranges and choices, for validate() (values set in code too);
 *   keyTable - the markdown table of the docs (a test keeps docs/ equal to it).
 * What a range cannot say (one key against another) stays in validate().
 */
#pragma once

#include <shadyloc/core/Settings.h>

#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace shadyloc::core
{
/** The values a numeric key allows. text() is both the error ("must be " +
 * text) and the docs' range column. */
class Range
{
   public:
	static Range any() { return {}; }
	static Range atLeast(double lo) { return {lo, kInf, false, false}; }	//!< >= lo
	static Range above(double lo) { return {lo, kInf, true, false}; }  //!< > lo
	static Range atMost(double hi) { return {-kInf, hi, false, false}; }  //!< <= hi
	static Range below(double hi) { return {-kInf, hi, false, true}; }  //!< < hi
	static Range closed(double lo, double hi) { return {lo, hi, false, false}; }	//!< [lo, hi]
	static Range openClosed(double lo, double hi) { return {lo, hi, true, false}; }	 //!< (lo, hi]
	static Range closedOpen(double lo, double hi) { return {lo, hi, false, true}; }	 //!< [lo, hi)
	static Range open(double lo, double hi) { return {lo, hi, true, true}; }	//!< (lo, hi)
	/** 0 allowed besides the range (0 = off). */
	Range orOff() const
	{
		Range r = *this;
		r.m_zeroOff = true;
		return r;
	}

	bool contains(double x) const;
	/** ">= 0", "in (0, 1]", "0 (off) or in [2, 1000]"; "" for any. */
	std::string text() const;
	bool bounded() const { return m_lo > -kInf || m_hi < kInf; }

   private:
	static constexpr double kInf = std::numeric_limits<double>::infinity();
	Range() = default;
	Range(double lo, double hi, bool loOpen, bool hiOpen) : m_lo(lo), m_hi(hi), m_loOpen(loOpen), m_hiOpen(hiOpen) {}

	double m_lo = -kInf, m_hi = kInf;
	bool m_loOpen = false, m_hiOpen = false, m_zeroOff = false;
};

/** One key as declared: name, unit ("" for none), range, comment. */
struct KeyDef
{
	const char* name;
	const char* unit;
	Range range;
	std::string doc;
	bool written = true;  //!< false: read, checked and documented, left out of the dump

	/** The dump's comment: doc, then "[unit]". */
	std::string comment() const;
};

/** A list of names, written "a b c" and read split at blanks and commas. */
using Words = std::vector<std::string>;

/** What an options struct's keys(KeyVisitor&) calls, once per key. */
class KeyVisitor
{
   public:
	/** A reference to one key's field, whatever its type. */
	using Field = std::variant<
		double*, float*, bool*, std::string*, short*, unsigned short*, int*, unsigned*, long*,
		unsigned long*, long long*, unsigned long long*, Words*>;

	virtual ~KeyVisitor() = default;

	/** written = false leaves the key out of the dump (one of two
	 * alternative keys, say); it is read, checked and documented as usual. */
	template <typename T>
	void operator()(const char* name, T& v, const char* unit, const Range& range, std::string doc, bool written = true)
	{
		key(KeyDef{name, unit, range, std::move(doc), written}, Field(&v));
	}

	/** A key spelt as one of a set of names (any case when read), each
	 * standing for a value (an enum, say). */
	template <typename E>
	void choice(
		const char* name, E& v, const std::vector<std::pair<std::string, E>>& choices, std::string doc)
	{
		std::vector<std::string> names;
		std::string cur;  // "" when v is none of them: checkKeys names it
		for (const auto& c : choices)
		{
			names.push_back(c.first);
			if (c.second == v) cur = c.first;
		}
		choiceKey(KeyDef{name, "", Range::any(), std::move(doc)}, cur, names);
		for (const auto& c : choices)  // only a reader changes cur
			if (c.first == cur && !(c.second == v)) v = c.second;
	}
	/** A string that must be one of `names` (any case when read). */
	void choice(const char* name, std::string& v, const std::vector<std::string>& names, std::string doc)
	{
		choiceKey(KeyDef{name, "", Range::any(), std::move(doc)}, v, names);
	}

	/** A key whose value is written as text by format(v) and read by
	 * parse(text), which throws std::invalid_argument saying what is wrong. */
	template <typename T, typename Format, typename Parse>
	void text(const char* name, T& v, Format format, Parse parse, std::string doc)
	{
		std::string t = format(v);
		textKey(KeyDef{name, "", Range::any(), std::move(doc)}, t, [&](const std::string& x) { v = parse(x); });
	}

	/** Keys renamed in an earlier version (the reader refuses the old names). */
	virtual void renamed(const std::vector<TRenamedKey>&) {}
	/** Keys of the section that another reader reads. */
	virtual void alsoKnown(std::initializer_list<const char*>) {}

   protected:
	virtual void key(const KeyDef& k, Field v) = 0;
	virtual void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) = 0;
	/** t: the value as text; set parses and assigns a new one (readers only). */
	virtual void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) = 0;
};

/** Reads the declared keys present in r (no range check: see loadKeys). */
class KeyReader : public KeyVisitor
{
   public:
	explicit KeyReader(SettingsSection& r) : m_r(r) {}
	void renamed(const std::vector<TRenamedKey>& t) override { m_r.renamed(t); }
	void alsoKnown(std::initializer_list<const char*> keys) override { m_r.alsoKnown(keys); }

   protected:
	void key(const KeyDef& k, Field v) override;
	void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) override;
	void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) override;

   private:
	SettingsSection& m_r;
};

/** Writes every key (comment, then "key = value") but those in leaveOut. */
class KeyWriter : public KeyVisitor
{
   public:
	explicit KeyWriter(SettingsWriter& w, std::vector<std::string> leaveOut = {})
		: m_w(w), m_leaveOut(std::move(leaveOut))
	{
	}

   protected:
	void key(const KeyDef& k, Field v) override;
	void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) override;
	void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) override;

   private:
	bool leftOut(const KeyDef& k) const;

	SettingsWriter& m_w;
	std::vector<std::string> m_leaveOut;
};

/** Throws std::invalid_argument "key: must be ..." for the first value out
 * of its range or choices. */
class KeyChecker : public KeyVisitor
{
   protected:
	void key(const KeyDef& k, Field v) override;
	void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) override;
	void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) override;
};

/** One row of the docs' table per key. */
class KeyTabler : public KeyVisitor
{
   public:
	std::string table() const;

   protected:
	void key(const KeyDef& k, Field v) override;
	void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) override;
	void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) override;

   private:
	std::vector<std::vector<std::string>> m_rows;
};

/** Each key with its value as the canonical dump writes it. */
class KeyTexter : public KeyVisitor
{
   public:
	std::vector<std::pair<std::string, std::string>> texts;

   protected:
	void key(const KeyDef& k, Field v) override;
	void choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names) override;
	void textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set) override;
};

/** The visitors only read through a const struct (keys() takes it non-const
 * so that one declaration serves reading too). */
template <typename T>
T& keysOf(const T& o)
{
	return const_cast<T&>(o);
}

template <typename T>
void readKeys(SettingsSection& r, T& o)
{
	KeyReader v(r);
	o.keys(v);
}

template <typename T>
void writeKeys(SettingsWriter& w, const T& o)
{
	KeyWriter v(w);
	keysOf(o).keys(v);
}

/** Ranges and choices of o's keys; throws std::invalid_argument "key: must be ...". */
template <typename T>
void checkKeys(const T& o)
{
	KeyChecker v;
	keysOf(o).keys(v);
}

/** Runs validate (std::invalid_argument "key: why") with r's file and section
 * in front of its message, as a SettingsError. */
template <typename F>
void validateAt(const SettingsSection& r, F&& validate)
{
	try
	{
		validate();
	}
	catch (const SettingsError&)
	{
		throw;
	}
	catch (const std::exception& e)
	{
		throw SettingsError(r.where() + " " + e.what());
	}
}

/** Reads o's keys from `section`, refuses unknown keys, then o.validate(). */
template <typename T>
void loadKeys(T& o, const mrpt::config::CConfigFileBase& c, const std::string& section)
{
	SettingsSection r(c, section);
	readKeys(r, o);
	r.finish();
	validateAt(r, [&] { o.validate(); });
}

template <typename T>
void dumpKeys(const T& o, std::ostream& out)
{
	SettingsWriter w(out);
	writeKeys(w, o);
}

/** (key, value as dumped) of every key of o, in order. */
template <typename T>
std::vector<std::pair<std::string, std::string>> keyTexts(const T& o)
{
	KeyTexter v;
	keysOf(o).keys(v);
	return v.texts;
}

/** The markdown table of o's keys: key, default (o's value), unit, range, meaning. */
template <typename T>
std::string keyTable(const T& o)
{
	KeyTabler v;
	keysOf(o).keys(v);
	return v.table();
}

}  // namespace shadyloc::core

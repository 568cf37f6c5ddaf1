/* ShadyLoc — the one strict reader and canonical writer of .ini settings.
 *
 * MRPT's readers are lenient in ways that change behaviour silently: a key
 * the program does not know (a typo) is ignored, "true ; comment" reads as
 * false, "1e308" as an int becomes 1, "abc" as a double becomes 0, and an
 * out-of-range integer wraps. Every options struct of the library reads its
 * section through SettingsSection instead:
 *
 *   - an inline comment (from the first ';' or '#') is stripped from every value;
 *   - numbers must parse completely, be finite and fit the target type;
 *   - booleans are true/false, 1/0 or yes/no (any case), nothing else;
 *   - choices must be one of a listed set;
 *   - after reading, finish() rejects any key in the section that no reader
 *     declared, and keys renamed in an earlier version are refused with the
 *     new name;
 *   - checkSections() rejects sections a command does not know (a misspelt
 *     section would otherwise be ignored as a whole) and, in a file, a key
 *     given twice in one section.
 *
 * Every error is a SettingsError whose what() names the file (when the
 * settings came from one), the section and the key.
 *
 * SettingsWriter writes the canonical form that loads back to the same
 * values: doubles in the shortest text that round-trips, booleans as
 * true/false, comments on their own lines (never after a value).
 */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <cstdint>
#include <initializer_list>
#include <limits>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace shadyloc::core
{
/** A bad settings file or value; what() names file, section and key. */
class SettingsError : public std::invalid_argument
{
   public:
	using std::invalid_argument::invalid_argument;
};

/** The file a config was read from (CConfigFile), or "" (in-memory text). */
std::string settingsSource(const mrpt::config::CConfigFileBase& c);

/** "'source': msg", unless msg already starts with that (or source is ""). */
std::string withSource(const std::string& source, const std::string& msg);

/** Config files given in order (`-c a.ini -c b.ini`) as one text: a section
 * may continue in a later file and a key given again in a later file
 * overrides (MRPT keeps the last of two equal keys). Each file must exist
 * and give no key twice within itself (SettingsError naming file and lines). */
std::string layeredConfigText(const std::vector<std::string>& paths);

/** A key renamed in an earlier version: the old name is refused naming the new. */
struct TRenamedKey
{
	std::string from;  //!< old key
	std::string to;	 //!< its new name
	std::string section = "";  //!< where it lives now, when it moved out of this section
};

/** Strict reader of one section. Each read*() declares its key as known and,
 * if the key is present, parses it into the value; an absent key leaves the
 * value untouched (the default). finish() then rejects unknown keys. */
class SettingsSection
{
   public:
	/** source: the file name for messages; by default settingsSource(c). */
	SettingsSection(const mrpt::config::CConfigFileBase& c, std::string section);
	SettingsSection(
		const mrpt::config::CConfigFileBase& c, std::string section, std::string source);

	const std::string& section() const { return m_section; }
	const std::string& source() const { return m_source; }
	const mrpt::config::CConfigFileBase& config() const { return m_c; }

	/** True if key is present; declares it known. */
	bool has(const std::string& key);

	void read(const std::string& key, double& v);
	void read(const std::string& key, float& v);
	void read(const std::string& key, bool& v);
	void read(const std::string& key, std::string& v);
	/** Any integer type: decimal (or 0x hexadecimal), in the type's range. */
	template <typename T>
	std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>> read(
		const std::string& key, T& v)
	{
		if (!has(key)) return;
		if constexpr (std::is_signed_v<T>)
		{
			const long long x = parseSigned(
				key, std::numeric_limits<T>::min(), std::numeric_limits<T>::max());
			v = static_cast<T>(x);
		}
		else
		{
			const unsigned long long x = parseUnsigned(key, std::numeric_limits<T>::max());
			v = static_cast<T>(x);
		}
	}

	/** One of a set of names (any case), each mapped to a value (an enum, say). */
	template <typename E>
	void readChoice(const std::string& key, E& v, const std::vector<std::pair<std::string, E>>& choices)
	{
		if (!has(key)) return;
		const std::string t = text(key);
		for (const auto& c : choices)
			if (sameName(c.first, t))
			{
				v = c.second;
				return;
			}
		std::vector<std::string> names;
		for (const auto& c : choices) names.push_back(c.first);
		badChoice(key, t, names);
	}
	/** One of a set of strings (any case); v takes the spelling of the set. */
	void readChoice(const std::string& key, std::string& v, const std::vector<std::string>& allowed);

	/** The value of a present key, inline comment stripped, trimmed. */
	std::string text(const std::string& key) const;

	/** Keys of this section read by another reader (declared known here). */
	void alsoKnown(std::initializer_list<const char*> keys);
	/** Refuses every old key present, naming its new name. Call before reads. */
	void renamed(const std::vector<TRenamedKey>& table);
	/** Throws SettingsError for the first key no reader declared. */
	void finish() const;

	/** "'file': [section] key" (no file part for in-memory settings). */
	std::string where(const std::string& key = "") const;
	/** Throws SettingsError "<where(key)>: what". */
	[[noreturn]] void fail(const std::string& key, const std::string& what) const;

   private:
	static bool sameName(const std::string& a, const std::string& b);
	long long parseSigned(const std::string& key, long long lo, long long hi) const;
	unsigned long long parseUnsigned(const std::string& key, unsigned long long hi) const;
	[[noreturn]] void badValue(const std::string& key, const std::string& txt, const std::string& want) const;
	[[noreturn]] void badChoice(
		const std::string& key, const std::string& txt, const std::vector<std::string>& names) const;

	const mrpt::config::CConfigFileBase& m_c;
	std::string m_section, m_source;
	std::set<std::string> m_known;
};

/** Throws SettingsError naming the first section of c that is not in
 * `known` (with the closest known one as a hint), or a key given before any
 * section. When c was read from a file, a key given twice in one section is
 * an error too (MRPT would keep the last silently). `what` says whose
 * settings they are (e.g. "VO config"). */
void checkSections(
	const mrpt::config::CConfigFileBase& c, const std::vector<std::string>& known,
	const std::string& what);

/** Shortest decimal text that parses back to exactly v (std::to_chars);
 * throws std::invalid_argument for NaN and infinities. */
std::string formatSetting(double v);

/** Writes settings in the canonical form SettingsSection reads back to the
 * same values. A comment goes on its own lines, before its key. */
class SettingsWriter
{
   public:
	explicit SettingsWriter(std::ostream& out) : m_out(out) {}

	/** "[name]", preceded by a blank line unless it is the first output. */
	void section(const std::string& name);
	/** Each line of text as "; line". */
	void comment(const std::string& text);

	void value(const std::string& key, double v, const std::string& comment = "");
	void value(const std::string& key, bool v, const std::string& comment = "");
	/** A string that would not read back (';', '#', a line break, or
	 * surrounding blanks) throws std::invalid_argument naming the key. */
	void value(const std::string& key, const std::string& v, const std::string& comment = "");
	void value(const std::string& key, const char* v, const std::string& comment = "")
	{
		value(key, std::string(v), comment);
	}
	template <typename T>
	std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>> value(
		const std::string& key, T v, const std::string& comment = "")
	{
		line(key, std::to_string(v), comment);
	}

   private:
	void line(const std::string& key, const std::string& v, const std::string& comment);
	std::ostream& m_out;
	bool m_any = false;
};

}  // namespace shadyloc::core

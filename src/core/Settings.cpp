/* ShadyLoc — the strict settings reader and the canonical writer. */
#include <shadyloc/core/Settings.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/system/string_utils.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace shadyloc::core
{
namespace
{
std::string lower(std::string s)
{
	std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
	return s;
}

/** Levenshtein distance, for "did you mean" hints. */
size_t editDistance(const std::string& a, const std::string& b)
{
	std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
	for (size_t j = 0; j <= b.size(); j++) prev[j] = j;
	for (size_t i = 1; i <= a.size(); i++)
	{
		cur[0] = i;
		for (size_t j = 1; j <= b.size(); j++)
			cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
		std::swap(prev, cur);
	}
	return prev[b.size()];
}

/** The known name closest to `name` if it is plausibly a misspelling of it
 * (same letters in another case, or at most a third of it edited), else "". */
std::string closest(const std::string& name, const std::vector<std::string>& known)
{
	std::string best;
	size_t bestD = std::string::npos;
	for (const auto& k : known)
	{
		const size_t d = lower(k) == lower(name) ? 0 : editDistance(lower(name), lower(k));
		if (d < bestD) bestD = d, best = k;
	}
	if (best.empty() || bestD > std::max<size_t>(2, name.size() / 3)) return "";
	return best;
}

std::string joined(const std::vector<std::string>& v, const char* sep = ", ")
{
	std::string s;
	for (size_t i = 0; i < v.size(); i++) s += (i ? sep : "") + v[i];
	return s;
}

std::string filePrefix(const std::string& source)
{
	return source.empty() ? std::string() : "'" + source + "': ";
}
}  // namespace

std::string settingsSource(const mrpt::config::CConfigFileBase& c)
{
	if (const auto* f = dynamic_cast<const mrpt::config::CConfigFile*>(&c)) return f->getAssociatedFile();
	return "";
}

std::string withSource(const std::string& source, const std::string& msg)
{
	const std::string pre = filePrefix(source);
	return msg.rfind(pre, 0) == 0 ? msg : pre + msg;
}

// ---- reader -------------------------------------------------------------------
SettingsSection::SettingsSection(const mrpt::config::CConfigFileBase& c, std::string section)
	: SettingsSection(c, std::move(section), settingsSource(c))
{
}

SettingsSection::SettingsSection(
	const mrpt::config::CConfigFileBase& c, std::string section, std::string source)
	: m_c(c), m_section(std::move(section)), m_source(std::move(source))
{
}

std::string SettingsSection::where(const std::string& key) const
{
	return filePrefix(m_source) + "[" + m_section + "]" + (key.empty() ? "" : " " + key);
}

void SettingsSection::fail(const std::string& key, const std::string& what) const
{
	throw SettingsError(where(key) + ": " + what);
}

void SettingsSection::badValue(const std::string& key, const std::string& txt, const std::string& want) const
{
	fail(key, "'" + txt + "' is not " + want);
}

void SettingsSection::badChoice(
	const std::string& key, const std::string& txt, const std::vector<std::string>& names) const
{
	badValue(key, txt, "one of: " + joined(names, " | "));
}

bool SettingsSection::has(const std::string& key)
{
	m_known.insert(key);
	return m_c.keyExists(m_section, key);
}

std::string SettingsSection::text(const std::string& key) const
{
	std::string v = m_c.read_string(m_section, key, "");
	// MRPT keeps an inline comment as part of the value (and then reads
	// "true ; comment" as false): everything from ';' or '#' is a comment.
	const size_t cut = v.find_first_of(";#");
	if (cut != std::string::npos) v.resize(cut);
	return mrpt::system::trim(v);
}

void SettingsSection::read(const std::string& key, double& v)
{
	if (!has(key)) return;
	const std::string t = text(key);
	const char* b = t.data();
	const char* e = b + t.size();
	if (b != e && *b == '+') b++;	// from_chars takes '-' but not '+'
	double x = 0;
	const auto r = std::from_chars(b, e, x, std::chars_format::general);
	if (t.empty() || r.ec == std::errc::invalid_argument || r.ptr != e) badValue(key, t, "a number");
	if (r.ec == std::errc::result_out_of_range || !std::isfinite(x))
		badValue(key, t, "a finite number in the range of a double");
	v = x;
}

void SettingsSection::read(const std::string& key, float& v)
{
	if (!has(key)) return;
	double d = v;
	read(key, d);
	if (std::abs(d) > std::numeric_limits<float>::max())
		badValue(key, text(key), "a number in the range of a float");
	v = static_cast<float>(d);
}

void SettingsSection::read(const std::string& key, bool& v)
{
	if (!has(key)) return;
	const std::string t = text(key);
	const std::string l = lower(t);
	if (l == "true" || l == "1" || l == "yes")
		v = true;
	else if (l == "false" || l == "0" || l == "no")
		v = false;
	else
		badValue(key, t, "a boolean (true/false, 1/0, yes/no)");
}

void SettingsSection::read(const std::string& key, std::string& v)
{
	if (has(key)) v = text(key);
}

void SettingsSection::readChoice(
	const std::string& key, std::string& v, const std::vector<std::string>& allowed)
{
	if (!has(key)) return;
	const std::string t = text(key);
	for (const auto& a : allowed)
		if (sameName(a, t))
		{
			v = a;
			return;
		}
	badChoice(key, t, allowed);
}

bool SettingsSection::sameName(const std::string& a, const std::string& b) { return lower(a) == lower(b); }

long long SettingsSection::parseSigned(const std::string& key, long long lo, long long hi) const
{
	const std::string t = text(key);
	const std::string want = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
	const char* b = t.data();
	const char* e = b + t.size();
	bool neg = false;
	if (b != e && (*b == '+' || *b == '-')) neg = (*b++ == '-');
	int base = 10;
	if (e - b > 2 && b[0] == '0' && (b[1] == 'x' || b[1] == 'X')) b += 2, base = 16;
	unsigned long long mag = 0;
	const auto r = std::from_chars(b, e, mag, base);
	if (b == e || r.ec != std::errc() || r.ptr != e) badValue(key, t, want);
	// |lo| = hi + 1 for two's complement types.
	const unsigned long long limit =
		neg ? static_cast<unsigned long long>(-(lo + 1)) + 1 : static_cast<unsigned long long>(hi);
	if (mag > limit) badValue(key, t, want);
	return neg ? (mag == 0 ? 0 : -static_cast<long long>(mag - 1) - 1) : static_cast<long long>(mag);
}

unsigned long long SettingsSection::parseUnsigned(const std::string& key, unsigned long long hi) const
{
	const std::string t = text(key);
	const std::string want = "an integer in [0, " + std::to_string(hi) + "]";
	const char* b = t.data();
	const char* e = b + t.size();
	if (b != e && *b == '+') b++;
	int base = 10;
	if (e - b > 2 && b[0] == '0' && (b[1] == 'x' || b[1] == 'X')) b += 2, base = 16;
	unsigned long long x = 0;
	const auto r = std::from_chars(b, e, x, base);
	if (b == e || r.ec != std::errc() || r.ptr != e || x > hi) badValue(key, t, want);
	return x;
}

void SettingsSection::alsoKnown(std::initializer_list<const char*> keys)
{
	for (const char* k : keys) m_known.insert(k);
}

void SettingsSection::renamed(const std::vector<TRenamedKey>& table)
{
	for (const auto& r : table)
	{
		// Exact spelling only: MRPT matches keys ignoring case, and the old
		// and new name may differ in case alone (e.g. a unit suffix "_K").
		std::vector<std::string> keys;
		m_c.getAllKeys(m_section, keys);
		if (std::find(keys.begin(), keys.end(), r.from) != keys.end())
			fail(r.from, r.section.empty()
							 ? "this key was renamed to '" + r.to + "' (same meaning and unit); rename it"
							 : "this key moved to '" + r.to + "' in " + r.section + "; move it there");
	}
}

void SettingsSection::finish() const
{
	std::vector<std::string> keys;
	m_c.getAllKeys(m_section, keys);
	const std::vector<std::string> known(m_known.begin(), m_known.end());
	for (const auto& k : keys)
	{
		if (m_known.count(k)) continue;
		const std::string hint = closest(k, known);
		fail(k, hint.empty() ? "unknown key (known: " + joined(known) + ")"
							 : "unknown key; did you mean '" + hint + "'?");
	}
}

// ---- whole file -----------------------------------------------------------------
namespace
{
/** MRPT keeps the last of two equal keys in a section (ignoring case) without
 * a word; in a file, that is almost always an edit gone wrong. */
void rejectDuplicateKeys(const std::string& path)
{
	std::ifstream in(path);
	std::map<std::string, std::map<std::string, size_t>> seen;	 // section -> key -> line
	std::string section, sectionName, line;
	for (size_t n = 1; std::getline(in, line); n++)
	{
		const std::string t = mrpt::system::trim(line);
		if (t.empty() || t[0] == ';' || t[0] == '#' || t[0] == '@') continue;
		if (t[0] == '[')
		{
			const size_t close = t.find(']');
			if (close != std::string::npos)
			{
				sectionName = mrpt::system::trim(t.substr(1, close - 1));
				section = lower(sectionName);
			}
			continue;
		}
		const size_t eq = t.find('=');
		if (eq == std::string::npos) continue;
		const std::string key = mrpt::system::trim(t.substr(0, eq));
		auto [it, fresh] = seen[section].emplace(lower(key), n);
		if (!fresh)
			throw SettingsError(
				"'" + path + "': [" + sectionName + "] " + key + ": given twice (lines " +
				std::to_string(it->second) + " and " + std::to_string(n) + ")");
	}
}
}  // namespace

std::string layeredConfigText(const std::vector<std::string>& paths)
{
	std::string text;
	for (const auto& p : paths)
	{
		std::ifstream f(p, std::ios::binary);
		if (!f) throw SettingsError("config file '" + p + "' does not exist or cannot be read");
		rejectDuplicateKeys(p);
		std::ostringstream s;
		s << f.rdbuf();
		text += s.str() + "\n";
	}
	return text;
}

void checkSections(
	const mrpt::config::CConfigFileBase& c, const std::vector<std::string>& known, const std::string& what)
{
	const std::string file = filePrefix(settingsSource(c));
	if (!settingsSource(c).empty()) rejectDuplicateKeys(settingsSource(c));
	std::vector<std::string> sections;
	c.getAllSections(sections);
	for (const auto& s : sections)
	{
		if (std::find(known.begin(), known.end(), s) != known.end()) continue;
		if (s.empty())
		{
			std::vector<std::string> keys;
			c.getAllKeys(s, keys);
			if (keys.empty()) continue;
			throw SettingsError(file + "key '" + keys.front() + "' before any [section]");
		}
		const std::string hint = closest(s, known);
		throw SettingsError(
			file + "[" + s + "]: unknown section in a " + what +
			(hint.empty() ? " (known: " + joined(known) + ")" : "; did you mean [" + hint + "]?"));
	}
}

// ---- writer -----------------------------------------------------------------------
std::string formatSetting(double v)
{
	if (!std::isfinite(v)) throw std::invalid_argument("cannot write a non-finite setting value");
	char buf[64];
	const auto r = std::to_chars(buf, buf + sizeof(buf), v);
	return std::string(buf, r.ptr);
}

void SettingsWriter::section(const std::string& name)
{
	if (m_any) m_out << "\n";
	m_out << "[" << name << "]\n";
	m_any = true;
}

void SettingsWriter::comment(const std::string& text)
{
	std::istringstream in(text);
	std::string l;
	while (std::getline(in, l)) m_out << "; " << l << "\n";
	m_any = true;
}

void SettingsWriter::line(const std::string& key, const std::string& v, const std::string& c)
{
	if (!c.empty()) comment(c);
	m_out << key << " = " << v << "\n";
	m_any = true;
}

void SettingsWriter::value(const std::string& key, double v, const std::string& c)
{
	if (!std::isfinite(v)) throw std::invalid_argument(key + ": cannot write a non-finite value");
	line(key, formatSetting(v), c);
}

void SettingsWriter::value(const std::string& key, bool v, const std::string& c)
{
	line(key, v ? "true" : "false", c);
}

void SettingsWriter::value(const std::string& key, const std::string& v, const std::string& c)
{
	if (v.find_first_of(";#\r\n") != std::string::npos || mrpt::system::trim(v) != v)
		throw std::invalid_argument(
			key + " = '" + v + "': cannot be written as a setting (';', '#', line breaks and "
			"surrounding blanks do not read back)");
	line(key, v, c);
}

}  // namespace shadyloc::core

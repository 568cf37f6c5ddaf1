/* ShadyLoc — the visitors of options keys (see Options.h). */
#include <shadyloc/core/Options.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace shadyloc::core
{
// ---- range ------------------------------------------------------------------------
bool Range::contains(double x) const
{
	if (m_zeroOff && x == 0) return true;
	if (!bounded()) return true;
	const bool loOk = m_loOpen ? x > m_lo : x >= m_lo;
	const bool hiOk = m_hiOpen ? x < m_hi : x <= m_hi;
	return loOk && hiOk;  // false for NaN
}

std::string Range::text() const
{
	std::string t;
	if (m_lo == -kInf && m_hi == kInf) return m_zeroOff ? "" : t;
	if (m_hi == kInf)
		t = (m_loOpen ? "> " : ">= ") + formatSetting(m_lo);
	else if (m_lo == -kInf)
		t = (m_hiOpen ? "< " : "<= ") + formatSetting(m_hi);
	else
		t = std::string("in ") + (m_loOpen ? "(" : "[") + formatSetting(m_lo) + ", " + formatSetting(m_hi) +
			(m_hiOpen ? ")" : "]");
	return m_zeroOff ? "0 (off) or " + t : t;
}

std::string KeyDef::comment() const
{
	if (!*unit) return doc;
	return doc.empty() ? std::string("[") + unit + "]" : doc + " [" + unit + "]";
}

namespace
{
/** The value of a numeric field as a double; nullopt-like false for the others. */
bool numberOf(const KeyVisitor::Field& f, double& x)
{
	return std::visit(
		[&](auto* p) {
			using T = std::remove_pointer_t<decltype(p)>;
			if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
			{
				x = static_cast<double>(*p);
				return true;
			}
			else
				return false;
		},
		f);
}

std::string joinedWords(const Words& v)
{
	std::string s;
	for (const auto& x : v) s += (s.empty() ? "" : " ") + x;
	return s;
}

Words splitWords(const std::string& s)
{
	Words out;
	std::string w;
	for (const char c : s + " ")
		if (c == ' ' || c == ',' || c == '\t')
		{
			if (!w.empty()) out.push_back(w);
			w.clear();
		}
		else
			w += c;
	return out;
}

/** w.value for every field type. */
template <typename T>
void writeValue(SettingsWriter& w, const KeyDef& k, const T& v, const std::string& comment)
{
	if constexpr (std::is_same_v<T, Words>)
		w.value(k.name, joinedWords(v), comment);
	else
		w.value(k.name, v, comment);
}

/** The value as the canonical dump writes it. */
std::string textOf(const KeyDef& k, const KeyVisitor::Field& f)
{
	std::ostringstream s;
	SettingsWriter w(s);
	std::visit([&](auto* p) { writeValue(w, k, *p, ""); }, f);
	std::string line = s.str();  // "name = value\n"
	return line.substr(std::string(k.name).size() + 3, line.size() - std::string(k.name).size() - 4);
}

std::string joined(const std::vector<std::string>& v, const std::string& before, const std::string& after)
{
	std::string s;
	for (size_t i = 0; i < v.size(); i++) s += (i ? ", " : "") + before + v[i] + after;
	return s;
}

/** A table cell: '|' would end it. */
std::string cell(const std::string& t)
{
	std::string s;
	for (char c : t) s += c == '|' ? std::string("\\|") : std::string(1, c);
	return s;
}
}  // namespace

// ---- reader -------------------------------------------------------------------------
void KeyReader::key(const KeyDef& k, Field v)
{
	std::visit(
		[&](auto* p) {
			if constexpr (std::is_same_v<std::remove_pointer_t<decltype(p)>, Words>)
			{
				if (m_r.has(k.name)) *p = splitWords(m_r.text(k.name));
			}
			else
				m_r.read(k.name, *p);
		},
		v);
}

void KeyReader::choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names)
{
	m_r.readChoice(k.name, v, names);
}

void KeyReader::textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>& set)
{
	if (!m_r.has(k.name)) return;
	t = m_r.text(k.name);
	try
	{
		set(t);
	}
	catch (const std::invalid_argument& e)
	{
		m_r.fail(k.name, e.what());
	}
}

// ---- writer -------------------------------------------------------------------------
bool KeyWriter::leftOut(const KeyDef& k) const
{
	return std::find(m_leaveOut.begin(), m_leaveOut.end(), k.name) != m_leaveOut.end();
}

void KeyWriter::key(const KeyDef& k, Field v)
{
	if (!k.written || leftOut(k)) return;
	std::visit([&](auto* p) { writeValue(m_w, k, *p, k.comment()); }, v);
}

void KeyWriter::choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>&)
{
	if (!leftOut(k)) m_w.value(k.name, v, k.comment());
}

void KeyWriter::textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>&)
{
	if (!leftOut(k)) m_w.value(k.name, t, k.comment());
}

// ---- checker ------------------------------------------------------------------------
void KeyChecker::key(const KeyDef& k, Field v)
{
	double x = 0;
	if (!numberOf(v, x)) return;
	if (!std::isfinite(x)) throw std::invalid_argument(std::string(k.name) + ": must be a finite number");
	if (!k.range.contains(x))
		throw std::invalid_argument(std::string(k.name) + ": must be " + k.range.text());
}

void KeyChecker::choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names)
{
	for (const auto& n : names)
		if (n == v) return;
	throw std::invalid_argument(std::string(k.name) + ": must be one of: " + joined(names, "", ""));
}

void KeyChecker::textKey(const KeyDef&, std::string&, const std::function<void(const std::string&)>&) {}

// ---- texts ------------------------------------------------------------------------
void KeyTexter::key(const KeyDef& k, Field v)
{
	if (k.written) texts.emplace_back(k.name, textOf(k, v));
}

void KeyTexter::textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>&)
{
	texts.emplace_back(k.name, t);
}

void KeyTexter::choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>&)
{
	texts.emplace_back(k.name, v);
}

// ---- docs table ---------------------------------------------------------------------
void KeyTabler::key(const KeyDef& k, Field v)
{
	const std::string value = textOf(k, v);
	m_rows.push_back({std::string("`") + k.name + "`", value.empty() ? "`\"\"`" : "`" + value + "`", *k.unit ? k.unit : "-",
					  k.range.text().empty() ? "-" : k.range.text(), k.doc});
}

void KeyTabler::choiceKey(const KeyDef& k, std::string& v, const std::vector<std::string>& names)
{
	m_rows.push_back({std::string("`") + k.name + "`", "`" + v + "`", "-", joined(names, "`", "`"), k.doc});
}

void KeyTabler::textKey(const KeyDef& k, std::string& t, const std::function<void(const std::string&)>&)
{
	m_rows.push_back({std::string("`") + k.name + "`", t.empty() ? "`\"\"`" : "`" + t + "`", "-", "-", k.doc});
}

std::string KeyTabler::table() const
{
	std::string t = "| key | default | unit | range | meaning |\n|---|---|---|---|---|\n";
	for (const auto& r : m_rows)
	{
		for (const auto& c : r) t += "| " + cell(c) + " ";
		t += "|\n";
	}
	return t;
}

}  // namespace shadyloc::core

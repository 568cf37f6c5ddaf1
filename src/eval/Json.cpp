/* ShadyLoc — the evaluation's JSON files (Json.h). */
#include "Json.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <locale>
#include <sstream>

namespace shadyloc::eval
{
namespace
{
/** The binary subtype that marks a fixed-decimals number's text. */
constexpr std::uint8_t kFixedNumber = 0xfd;

bool isFixedNumber(const Json& v)
{
	return v.is_binary() && v.get_binary().has_subtype() && v.get_binary().subtype() == kFixedNumber;
}

/** A scalar as the library writes it: strings escaped (invalid UTF-8
 * replaced rather than thrown on: a path is written as well as it can be). */
std::string scalar(const Json& v) { return v.dump(-1, ' ', false, Json::error_handler_t::replace); }

/** A pointer's reference token for `key` (RFC 6901: "~" as "~0", "/" as "~1"). */
std::string token(const std::string& key)
{
	std::string t;
	for (const char c : key) t += c == '~' ? "~0" : (c == '/' ? "~1" : std::string(1, c));
	return t;
}

class Writer
{
   public:
	explicit Writer(const std::vector<std::string>& broken) : m_broken(broken) {}

	/** Writes v, found at `pointer` inside `level` broken containers. */
	void value(const Json& v, const std::string& pointer, int level)
	{
		if (isFixedNumber(v))
			m_out.append(v.get_binary().begin(), v.get_binary().end());
		else if (v.is_structured())
			container(v, pointer, level);
		else
			m_out += scalar(v);
	}
	std::string text() { return m_out + "\n"; }

   private:
	void container(const Json& v, const std::string& pointer, int level)
	{
		const bool broken = std::find(m_broken.begin(), m_broken.end(), pointer) != m_broken.end();
		const int inner = level + (broken ? 1 : 0);
		m_out += v.is_object() ? '{' : '[';
		size_t i = 0;
		for (auto it = v.begin(); it != v.end(); ++it, ++i)
		{
			if (broken)
				m_out += (i ? ",\n" : "\n") + std::string(2 * inner, ' ');
			else if (i)
				m_out += ", ";
			const std::string key = v.is_object() ? it.key() : std::to_string(i);
			if (v.is_object()) m_out += scalar(Json(key)) + ": ";
			value(*it, pointer + "/" + token(key), inner);
		}
		if (broken) m_out += "\n" + std::string(2 * level, ' ');
		m_out += v.is_object() ? '}' : ']';
	}

	const std::vector<std::string>& m_broken;
	std::string m_out;
};
}  // namespace

Json fixedNumber(double v, int decimals)
{
	if (!std::isfinite(v)) return nullptr;
	std::ostringstream s;
	s.imbue(std::locale::classic());  // a point, whatever the program's locale
	s << std::fixed << std::setprecision(decimals) << v;
	const std::string text = s.str();
	return Json::binary(std::vector<std::uint8_t>(text.begin(), text.end()), kFixedNumber);
}

std::string writeJson(const Json& doc, const std::vector<std::string>& broken)
{
	Writer w(broken);
	w.value(doc, "", 0);
	return w.text();
}

Json readJsonFile(const std::string& path)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) return nullptr;
	Json doc = Json::parse(f, nullptr, false);
	return doc.is_discarded() ? Json() : doc;
}

}  // namespace shadyloc::eval

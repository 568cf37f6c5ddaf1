/* ShadyLoc — JSON text of the evaluation's outputs. */
#include "Json.h"

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

namespace shadyloc::eval
{
std::string jsonString(const std::string& s)
{
	std::string o = "\"";
	for (const char c : s)
	{
		if (c == '"' || c == '\\')
			o += std::string("\\") + c;
		else if (c == '\n')
			o += "\\n";
		else if (static_cast<unsigned char>(c) < 0x20)
		{
			char b[8];
			std::snprintf(b, sizeof b, "\\u%04x", c);
			o += b;
		}
		else
			o += c;
	}
	return o + "\"";
}

std::string jsonNumber(double v, int prec)
{
	if (!std::isfinite(v)) return "null";
	std::ostringstream s;
	s << std::fixed << std::setprecision(prec) << v;
	return s.str();
}

}  // namespace shadyloc::eval

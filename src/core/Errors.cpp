/* ShadyLoc — the reason inside an MRPT exception's text. */
#include <shadyloc/core/Errors.h>

#include <sstream>

namespace shadyloc::core
{
std::string mrptReason(const std::string& what)
{
	const std::string banner = "==== MRPT exception ====";
	if (what.find(banner) == std::string::npos) return what;
	const std::string tag = "Original exception:\n";
	const auto at = what.rfind(tag);
	std::istringstream lines(at == std::string::npos ? what : what.substr(at + tag.size()));
	std::string reason, line;
	while (std::getline(lines, line))
	{
		if (line.rfind(banner, 0) == 0) continue;
		if (line.rfind("Location:", 0) == 0 || line.rfind("Call stack", 0) == 0) break;
		if (line.rfind("Message:", 0) == 0) line = line.substr(8);
		const auto b = line.find_first_not_of(" \t");
		if (b == std::string::npos)
		{
			if (!reason.empty()) break;	 // a blank line ends the message
			continue;
		}
		reason += (reason.empty() ? "" : " ") + line.substr(b);
	}
	return reason.empty() ? what : reason;
}
}  // namespace shadyloc::core

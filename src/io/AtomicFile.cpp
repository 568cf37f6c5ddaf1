/* ShadyLoc — write-then-rename. */
#include <shadyloc/io/AtomicFile.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace fs = std::filesystem;

namespace shadyloc::io
{
std::string temporarySibling(const std::string& path)
{
	const fs::path p(path);
	fs::path tmp = p.parent_path() / ("." + p.stem().string() + ".tmp" + p.extension().string());
	return tmp.string();
}

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
	const std::string tmp = temporarySibling(path);
	try
	{
		write(tmp);
		if (!fs::exists(tmp))
			throw std::runtime_error("'" + path + "': writer produced no output");
		fs::rename(tmp, path);
	}
	catch (...)
	{
		std::error_code ec;
		fs::remove(tmp, ec);
		throw;
	}
}

}  // namespace shadyloc::io

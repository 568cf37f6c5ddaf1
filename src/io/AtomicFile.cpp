/* ShadyLoc — write-then-rename, through a one-output transaction. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/OutputTransaction.h>

#include <fstream>
#include <stdexcept>

namespace shadyloc::io
{
std::string temporarySibling(const std::string& path) { return temporaryPathFor(path); }

void writeAtomically(const std::string& path, const std::function<void(const std::string&)>& write)
{
	OutputTransaction tx;
	const std::string tmp = tx.addFile(path);
	write(tmp);
	tx.commit();
}

void writeTextFile(const std::string& path, const std::string& text)
{
	writeAtomically(path, [&](const std::string& p) {
		std::ofstream f(p, std::ios::binary);
		f << text;
		f.close();
		if (!f) throw std::runtime_error("cannot write '" + p + "'");
	});
}

}  // namespace shadyloc::io

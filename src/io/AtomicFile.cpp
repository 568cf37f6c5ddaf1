/* ShadyLoc — write-then-rename, through a one-output transaction. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/OutputTransaction.h>

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

}  // namespace shadyloc::io

/* ShadyLoc — the outputs of one command, committed together or not at all.
 *
 * Every output (file or directory) is written to a temporary sibling first
 * (".<stem>.tmp-<pid><ext>", same directory, same extension so that
 * format-by-extension writers work). commit() moves the old outputs aside,
 * renames every temporary into place and then drops the old ones; if any
 * rename fails, what was renamed is undone and the old outputs come back.
 * Without commit() (an error, an early return) the destructor removes every
 * temporary. Temporaries are also registered for removal on SIGINT/SIGTERM
 * (io::installSignalCleanup), and temporaries left by a killed run are named,
 * with the command that deletes them, when an output goes to their directory.
 *
 * No output may be an input: each output is compared with the declared
 * inputs by canonical path (through symbolic links) and by device/inode
 * (hard links), and may not contain an input (a directory replaced as a
 * whole). Outputs may not coincide or nest either.
 *
 * A folder output carries a marker file (kOutputMarker) naming the kind of
 * output it is; an existing folder is replaced only if it is empty or
 * carries the same marker: a folder the user filled, or another command's
 * output, is refused with its name and left untouched.
 */
#pragma once

#include <mrpt/system/COutputLogger.h>

#include <cstdint>
#include <string>
#include <vector>

namespace shadyloc::io
{
class OutputTransaction : public mrpt::system::COutputLogger
{
   public:
	OutputTransaction();
	~OutputTransaction() override;
	OutputTransaction(const OutputTransaction&) = delete;
	OutputTransaction& operator=(const OutputTransaction&) = delete;

	/** Declares an input (file or directory; need not exist). `what` names
	 * it in messages, e.g. "input rawlog". Throws std::invalid_argument if an
	 * output already declared is this input. */
	void addInput(const std::string& path, const std::string& what = "input");

	/** Declares an input folder whose files the command lists and reads
	 * (e.g. every image in it): no output may lie anywhere inside it, or
	 * the next run would read that output as an input. */
	void addListedFolder(const std::string& path, const std::string& what);

	/** Reserves an output file; returns the temporary path to write it to.
	 * `what` names it in messages (e.g. "--stats"). Throws
	 * std::invalid_argument: empty path, directory missing, an existing
	 * directory at that path, an input, or another output of this command. */
	std::string addFile(const std::string& path, const std::string& what = "output");

	/** Reserves an output directory, replaced as a whole on commit(); returns
	 * the temporary directory (created, holding only the marker file). Same
	 * checks as addFile(); `kind` (e.g. "shadyloc localise output") is
	 * written to the marker, and an existing directory at `path` is refused
	 * (std::invalid_argument naming it) unless it is empty or its marker
	 * names the same kind. */
	std::string addDirectory(const std::string& path, const std::string& what, const std::string& kind);

	/** True if `path` is already an output of this transaction. */
	bool hasOutput(const std::string& path) const;

	/** Renames every temporary into place, all or none. Throws on failure
	 * (then nothing changed: old outputs are back, temporaries removed). */
	void commit();
	bool committed() const { return m_committed; }

	/** Removes every temporary now (what the destructor does). */
	void rollback();

   private:
	struct TEntry
	{
		std::string path, canonical, what;
		uint64_t dev = 0, ino = 0;	//!< of an existing file (hard links)
		bool isDir = false;
		bool listed = false;  //!< an input folder whose files are all read
		std::string tmp;  //!< outputs only
	};
	std::string reserve(const std::string& path, const std::string& what, bool dir, const std::string& kind = "");
	void checkAgainst(const TEntry& out, const TEntry& other, bool otherIsInput) const;
	void reportStale(const std::string& dir);

	std::vector<TEntry> m_inputs, m_outputs;
	std::vector<std::string> m_checkedDirs;	 //!< for stale temporaries
	bool m_committed = false;
};

/** The file that marks a folder as a command's output: ".shadyloc-output",
 * whose first line is the kind of output. */
extern const char* const kOutputMarker;

/** Throws std::invalid_argument (naming `path` as `what`) if `path` is an
 * existing directory that is neither empty nor marked as output of `kind`. */
void checkReplaceableFolder(const std::string& path, const std::string& what, const std::string& kind);

/** Writes the marker of `kind` into the directory `dir`. */
void markOutputFolder(const std::string& dir, const std::string& kind);

/** The temporary sibling this process uses for `path`: "dir/.<stem>.tmp-<pid><ext>". */
std::string temporaryPathFor(const std::string& path);

/** Temporaries (files or directories) removed if the process is interrupted. */
void registerTemporary(const std::string& path);
void unregisterTemporary(const std::string& path);

/** Makes SIGINT, SIGTERM, SIGHUP and SIGQUIT remove every registered
 * temporary, then end the process as the signal would have. Call once from
 * main() before any thread starts (the signals are handled by a thread of
 * their own, so the removal runs outside a signal handler). */
void installSignalCleanup();

/** Temporaries left in `dir` by runs that are no longer alive (killed, or
 * from an older version), as paths. */
std::vector<std::string> staleTemporaries(const std::string& dir);

}  // namespace shadyloc::io

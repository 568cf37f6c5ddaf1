/* ShadyLoc — per-frame results as CSV: a header line, then one line per row,
 * written atomically (a temporary sibling renamed into place on commit()). */
#pragma once

#include <fstream>
#include <string>

namespace shadyloc::io
{
/** A CSV file under construction. Rows go to a temporary sibling of `path`
 * (io::temporarySibling); commit() renames it into place. Without commit()
 * (an exception, an early return) the destructor deletes it: no half-written
 * file is ever left at `path`. The caller formats the fields (precision,
 * fixed/scientific) on out() and ends each row with '\n'. */
class CsvWriter
{
   public:
	/** Opens the temporary file and writes `header` (comma-separated column
	 * names, no newline). Throws std::runtime_error naming `path`. */
	CsvWriter(const std::string& path, const std::string& header);
	~CsvWriter();
	CsvWriter(const CsvWriter&) = delete;
	CsvWriter& operator=(const CsvWriter&) = delete;

	/** The stream rows are written to. */
	std::ostream& out() { return m_out; }
	/** Flushes, closes and renames into place (replacing an old file);
	 * throws naming `path` if anything failed to write (disk full?). */
	void commit();

	const std::string& path() const { return m_path; }

   private:
	std::string m_path, m_tmp;
	std::ofstream m_out;
	bool m_committed = false;
};

}  // namespace shadyloc::io

/* ShadyLoc — atomic CSV files. */
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/io/Csv.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace fs = std::filesystem;

namespace shadyloc::io
{
CsvWriter::CsvWriter(const std::string& path, const std::string& header)
	: m_path(path), m_tmp(temporarySibling(path))
{
	m_out.open(m_tmp);
	if (!m_out) throw std::runtime_error("'" + path + "': cannot create CSV file ('" + m_tmp + "')");
	m_out << header << '\n';
}

CsvWriter::~CsvWriter()
{
	if (m_committed) return;
	m_out.close();
	std::error_code ec;
	fs::remove(m_tmp, ec);
}

void CsvWriter::commit()
{
	m_out.close();
	if (!m_out) throw std::runtime_error("'" + m_path + "': write failed (disk full?)");
	fs::rename(m_tmp, m_path);
	m_committed = true;
}

}  // namespace shadyloc::io

#include <agex/io/input_file.h>

#include <sys/stat.h>

namespace agex
{
std::string
notARegularFile (const std::string &path)
{
  struct stat st;
  if (::stat (path.c_str (), &st) != 0 || S_ISREG (st.st_mode))
    return "";
  const char *what = S_ISDIR (st.st_mode)    ? "is a directory"
                     : S_ISFIFO (st.st_mode) ? "is a FIFO (named pipe)"
                     : S_ISSOCK (st.st_mode) ? "is a socket"
                     : S_ISCHR (st.st_mode)  ? "is a character device"
                     : S_ISBLK (st.st_mode)  ? "is a block device"
                                             : "is not a file";
  return std::string (what) + ", not a regular file";
}
}  // namespace agex

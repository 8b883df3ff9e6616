#include <agex/landmarks/imglab_dataset.h>
#include <agex/io/atomic_file.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace agex
{
namespace
{
// Just enough XML for imglab files: elements, attributes, text, comments, processing
// instructions and the five predefined entities. No namespaces, no DTDs.
// imglab nests 5 deep (dataset, images, image, box, part); the parser recurses once per
// level, so the depth is bounded well before a deep file could exhaust the stack.
constexpr int kMaxXmlDepth = 64;

struct XmlNode
{
  std::string name;
  std::map<std::string, std::string> attributes;
  std::vector<std::unique_ptr<XmlNode>> children;
  std::string text;
  int line = 0;
};

class XmlParser
{
public:
  XmlParser (std::string path, std::string text) : path_ (std::move (path)), text_ (std::move (text)) {}

  std::unique_ptr<XmlNode>
  parseDocument ()
  {
    std::unique_ptr<XmlNode> root;
    while (true)
    {
      skipMisc ();
      if (pos_ >= text_.size ())
        break;
      if (root)
        fail ("content after the root element");
      if (text_[pos_] != '<')
        fail ("text outside the root element");
      root = parseElement (1);
    }
    if (!root)
      fail ("no XML element (empty or not an XML file)");
    return root;
  }

  [[noreturn]] void
  fail (const std::string &problem) const
  {
    throw std::runtime_error (path_ + ": line " + std::to_string (lineAt (pos_)) + ": " + problem);
  }

private:
  // Counted on from the last position asked for (the parser moves forwards), so that a file
  // of many elements is read in linear time.
  int
  lineAt (std::size_t pos) const
  {
    pos = std::min (pos, text_.size ());
    if (pos < counted_pos_)
    {
      counted_pos_ = 0;
      counted_line_ = 1;
    }
    for (; counted_pos_ < pos; ++counted_pos_)
      counted_line_ += text_[counted_pos_] == '\n';
    return counted_line_;
  }

  bool startsWith (const char *s) const { return text_.compare (pos_, std::char_traits<char>::length (s), s) == 0; }

  void
  skipPast (const char *end, const char *what)
  {
    const std::size_t at = text_.find (end, pos_);
    if (at == std::string::npos)
      fail (std::string ("unterminated ") + what);
    pos_ = at + std::char_traits<char>::length (end);
  }

  void
  skipSpace ()
  {
    while (pos_ < text_.size () && std::isspace (static_cast<unsigned char> (text_[pos_])))
      ++pos_;
  }

  // Whitespace, comments, processing instructions and declarations between elements.
  void
  skipMisc ()
  {
    while (true)
    {
      skipSpace ();
      if (startsWith ("<?"))
        skipPast ("?>", "processing instruction");
      else if (startsWith ("<!--"))
        skipPast ("-->", "comment");
      else if (startsWith ("<!"))
        skipPast (">", "declaration");
      else
        return;
    }
  }

  std::string
  parseName ()
  {
    const std::size_t start = pos_;
    while (pos_ < text_.size () && (std::isalnum (static_cast<unsigned char> (text_[pos_])) || text_[pos_] == '_' ||
                                    text_[pos_] == '-' || text_[pos_] == ':' || text_[pos_] == '.'))
      ++pos_;
    if (pos_ == start)
      fail ("expected a name");
    return text_.substr (start, pos_ - start);
  }

  std::string
  decode (const std::string &raw) const
  {
    std::string out;
    for (std::size_t i = 0; i < raw.size (); ++i)
    {
      if (raw[i] != '&')
      {
        out += raw[i];
        continue;
      }
      const std::size_t end = raw.find (';', i);
      if (end == std::string::npos)
        fail ("unterminated entity in '" + raw + "'");
      const std::string entity = raw.substr (i + 1, end - i - 1);
      if (entity == "amp") out += '&';
      else if (entity == "lt") out += '<';
      else if (entity == "gt") out += '>';
      else if (entity == "quot") out += '"';
      else if (entity == "apos") out += '\'';
      else if (!entity.empty () && entity[0] == '#')
      {
        const long code = entity.size () > 1 && entity[1] == 'x' ? std::strtol (entity.c_str () + 2, nullptr, 16)
                                                                   : std::strtol (entity.c_str () + 1, nullptr, 10);
        if (code <= 0 || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF))
          fail ("invalid character reference &" + entity + ";");
        // Written as UTF-8, the encoding the files declare and file names use.
        if (code < 0x80)
          out += static_cast<char> (code);
        else if (code < 0x800)
          out += {static_cast<char> (0xC0 | code >> 6), static_cast<char> (0x80 | (code & 0x3F))};
        else if (code < 0x10000)
          out += {static_cast<char> (0xE0 | code >> 12), static_cast<char> (0x80 | (code >> 6 & 0x3F)),
                  static_cast<char> (0x80 | (code & 0x3F))};
        else
          out += {static_cast<char> (0xF0 | code >> 18), static_cast<char> (0x80 | (code >> 12 & 0x3F)),
                  static_cast<char> (0x80 | (code >> 6 & 0x3F)), static_cast<char> (0x80 | (code & 0x3F))};
      }
      else
        fail ("unknown entity &" + entity + ";");
      i = end;
    }
    return out;
  }

  std::unique_ptr<XmlNode>
  parseElement (int depth)
  {
    if (depth > kMaxXmlDepth)
      fail ("elements nested more than " + std::to_string (kMaxXmlDepth) +
            " deep (imglab datasets nest 5 deep; not an imglab dataset)");
    auto node = std::make_unique<XmlNode> ();
    node->line = lineAt (pos_);
    ++pos_;  // '<'
    node->name = parseName ();
    while (true)
    {
      skipSpace ();
      if (pos_ >= text_.size ())
        fail ("unterminated element <" + node->name + ">");
      if (startsWith ("/>"))
      {
        pos_ += 2;
        return node;
      }
      if (text_[pos_] == '>')
      {
        ++pos_;
        break;
      }
      const std::string attribute = parseName ();
      skipSpace ();
      if (pos_ >= text_.size () || text_[pos_] != '=')
        fail ("attribute '" + attribute + "' of <" + node->name + "> has no value");
      ++pos_;
      skipSpace ();
      if (pos_ >= text_.size () || (text_[pos_] != '\'' && text_[pos_] != '"'))
        fail ("attribute '" + attribute + "' of <" + node->name + "> is not quoted");
      const char quote = text_[pos_++];
      const std::size_t end = text_.find (quote, pos_);
      if (end == std::string::npos)
        fail ("unterminated value of attribute '" + attribute + "'");
      node->attributes[attribute] = decode (text_.substr (pos_, end - pos_));
      pos_ = end + 1;
    }
    // Content: text, child elements, comments, up to the matching end tag.
    while (true)
    {
      if (pos_ >= text_.size ())
        fail ("element <" + node->name + "> (line " + std::to_string (node->line) + ") is never closed");
      if (startsWith ("<!--"))
        skipPast ("-->", "comment");
      else if (startsWith ("<![CDATA["))
      {
        const std::size_t start = pos_ + 9;
        skipPast ("]]>", "CDATA section");
        node->text += text_.substr (start, pos_ - 3 - start);
      }
      else if (startsWith ("<?"))
        skipPast ("?>", "processing instruction");
      else if (startsWith ("</"))
      {
        pos_ += 2;
        const std::string name = parseName ();
        if (name != node->name)
          fail ("</" + name + "> closes <" + node->name + "> (line " + std::to_string (node->line) + ")");
        skipSpace ();
        if (pos_ >= text_.size () || text_[pos_] != '>')
          fail ("malformed end tag </" + name);
        ++pos_;
        return node;
      }
      else if (text_[pos_] == '<')
        node->children.push_back (parseElement (depth + 1));
      else
      {
        const std::size_t end = text_.find ('<', pos_);
        node->text += decode (text_.substr (pos_, end == std::string::npos ? std::string::npos : end - pos_));
        pos_ = end == std::string::npos ? text_.size () : end;
      }
    }
  }

  std::string path_;
  std::string text_;
  std::size_t pos_ = 0;
  mutable std::size_t counted_pos_ = 0;
  mutable int counted_line_ = 1;
};

std::string
trimmed (const std::string &s)
{
  const std::size_t begin = s.find_first_not_of (" \t\r\n");
  if (begin == std::string::npos)
    return "";
  return s.substr (begin, s.find_last_not_of (" \t\r\n") - begin + 1);
}

std::string
escaped (const std::string &s)
{
  std::string out;
  for (const char c : s)
    switch (c)
    {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '\'': out += "&apos;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  return out;
}

class ImglabReader
{
public:
  explicit ImglabReader (std::string path) : path_ (std::move (path)) {}

  [[noreturn]] void
  fail (const XmlNode &node, const std::string &problem) const
  {
    throw std::runtime_error (path_ + ": line " + std::to_string (node.line) + ": " + problem);
  }

  const std::string &
  attribute (const XmlNode &node, const std::string &name) const
  {
    const auto it = node.attributes.find (name);
    if (it == node.attributes.end ())
      fail (node, "<" + node.name + "> has no '" + name + "' attribute");
    return it->second;
  }

  double
  number (const XmlNode &node, const std::string &name) const
  {
    const std::string &text = attribute (node, name);
    char *end = nullptr;
    const double value = std::strtod (text.c_str (), &end);
    if (text.empty () || *end != '\0' || !std::isfinite (value))
      fail (node, "attribute '" + name + "' of <" + node.name + "> is not a number: '" + text + "'");
    return value;
  }

  /** A pixel coordinate: a finite number within +-kMaxImglabCoordinate (within [0, that] for
    * a size). Checked before any cast: as a float 1e300 is infinite, as an int 4294967643 is 347. */
  double
  coordinate (const XmlNode &node, const std::string &name, bool size = false) const
  {
    const double value = number (node, name);
    if (!(value >= (size ? 0.0 : -kMaxImglabCoordinate) && value <= kMaxImglabCoordinate))
      fail (node, "attribute '" + name + "' of <" + node.name + "> is " + attribute (node, name) + ", not a pixel " +
                    (size ? "size (0 to 1000000)" : "coordinate (within +-1000000)"));
    return value;
  }

  ImglabBox
  box (const XmlNode &node) const
  {
    ImglabBox box;
    box.line = node.line;
    box.rect = cv::Rect (static_cast<int> (std::lround (coordinate (node, "left"))),
                         static_cast<int> (std::lround (coordinate (node, "top"))),
                         static_cast<int> (std::lround (coordinate (node, "width", true))),
                         static_cast<int> (std::lround (coordinate (node, "height", true))));
    if (box.rect.width < 0 || box.rect.height < 0)
      fail (node, "box with a negative size");
    const auto ignore = node.attributes.find ("ignore");
    box.ignore = ignore != node.attributes.end () && ignore->second != "0" && ignore->second != "false";
    // A person box of no area has no scale: one such box wrecks a shape predictor's training.
    if (!box.ignore && (box.rect.width == 0 || box.rect.height == 0))
      fail (node, "box of zero width or height (mark it ignore='1' or give its size)");
    for (const auto &child : node.children)
      if (child->name == "label")
        box.label = trimmed (child->text);
      else if (child->name == "part")
      {
        const std::string &name = attribute (*child, "name");
        if (box.parts.count (name))
          fail (*child, "part '" + name + "' given twice in one box");
        box.parts[name] = cv::Point2f (static_cast<float> (coordinate (*child, "x")),
                                       static_cast<float> (coordinate (*child, "y")));
      }
    return box;
  }

  ImglabDataset
  dataset (const XmlNode &root) const
  {
    if (root.name != "dataset")
      fail (root, "the root element is <" + root.name + ">, not <dataset> (not an imglab dataset)");
    ImglabDataset dataset;
    for (const auto &child : root.children)
      if (child->name == "name")
        dataset.name = trimmed (child->text);
      else if (child->name == "comment")
        dataset.comment = trimmed (child->text);
      else if (child->name == "images")
        for (const auto &image_node : child->children)
        {
          if (image_node->name != "image")
            continue;
          ImglabImage image;
          image.file = attribute (*image_node, "file");
          if (image.file.empty ())
            fail (*image_node, "<image> with an empty file name");
          for (const auto &box_node : image_node->children)
            if (box_node->name == "box")
              image.boxes.push_back (box (*box_node));
          dataset.images.push_back (std::move (image));
        }
    return dataset;
  }

private:
  std::string path_;
};
}  // namespace

ImglabDataset
readImglabDataset (const std::string &path)
{
  std::ifstream in (path, std::ios::binary);
  if (!in)
    throw std::runtime_error (path + ": cannot open the imglab dataset");
  std::ostringstream bytes;
  bytes << in.rdbuf ();
  XmlParser parser (path, bytes.str ());
  const std::unique_ptr<XmlNode> root = parser.parseDocument ();
  return ImglabReader (path).dataset (*root);
}

std::string
imglabDatasetXml (const ImglabDataset &dataset)
{
  std::ostringstream out;
  out << "<?xml version='1.0' encoding='UTF-8'?>\n"
      << "<?xml-stylesheet type='text/xsl' href='image_metadata_stylesheet.xsl'?>\n"
      << "<dataset>\n"
      << "<name>" << escaped (dataset.name) << "</name>\n"
      << "<comment>" << escaped (dataset.comment) << "</comment>\n"
      << "<images>\n";
  for (const ImglabImage &image : dataset.images)
  {
    out << "  <image file='" << escaped (image.file) << "'>\n";
    for (const ImglabBox &box : image.boxes)
    {
      out << "    <box top='" << box.rect.y << "' left='" << box.rect.x << "' width='" << box.rect.width
          << "' height='" << box.rect.height << "'" << (box.ignore ? " ignore='1'" : "") << ">\n";
      if (!box.label.empty ())
        out << "      <label>" << escaped (box.label) << "</label>\n";
      for (const auto &[name, p] : box.parts)
        out << "      <part name='" << escaped (name) << "' x='" << std::lround (p.x) << "' y='" << std::lround (p.y)
            << "'/>\n";
      out << "    </box>\n";
    }
    out << "  </image>\n";
  }
  out << "</images>\n</dataset>\n";
  return out.str ();
}

void
writeImglabDataset (const std::string &path, const ImglabDataset &dataset)
{
  writeFileAtomic (path, imglabDatasetXml (dataset));
}

std::string
resolveImglabImagePath (const std::string &dataset_path, const std::string &file)
{
  const std::filesystem::path image (file);
  if (image.is_absolute ())
    return file;
  return (std::filesystem::path (dataset_path).parent_path () / image).string ();
}
}  // namespace agex

//! The XML structure of a VTK XML file: the root attributes, the pieces and
//! their `DataArray` elements, and where the appended data lies.
//!
//! Appended raw data is not XML, so only the part of the file before
//! `<AppendedData` goes through the XML parser; the `AppendedData` start tag
//! is parsed on its own and the data region (after the `_` marker) is located
//! by byte offsets.

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

/// Byte order of binary data (`byte_order` on `VTKFile`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ByteOrder {
    Little,
    Big,
}

/// Width of the integers in binary headers (`header_type`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum HeaderType {
    U32,
    U64,
}

impl HeaderType {
    pub(super) fn size(self) -> usize {
        match self {
            HeaderType::U32 => 4,
            HeaderType::U64 => 8,
        }
    }
}

/// Element type of a `DataArray`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
    F32,
    F64,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "Float32" => Scalar::F32,
            "Float64" => Scalar::F64,
            "Int8" => Scalar::I8,
            "Int16" => Scalar::I16,
            "Int32" => Scalar::I32,
            "Int64" => Scalar::I64,
            "UInt8" => Scalar::U8,
            "UInt16" => Scalar::U16,
            "UInt32" => Scalar::U32,
            "UInt64" => Scalar::U64,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::F32 | Scalar::I32 | Scalar::U32 => 4,
            Scalar::F64 | Scalar::I64 | Scalar::U64 => 8,
        }
    }
}

/// How a `DataArray` stores its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Format {
    Ascii,
    /// Inline base64.
    Binary,
    /// In `AppendedData`, at this offset from the `_` marker.
    Appended(usize),
}

/// One `DataArray` element.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ArraySpec {
    pub name: String,
    pub type_name: String,
    /// `None` for types that are not numbers (`String`, `Bit`).
    pub scalar: Option<Scalar>,
    pub components: usize,
    /// `NumberOfTuples`, when given (field data).
    pub tuples: Option<usize>,
    pub format: Format,
    /// The element's own text (ascii numbers or base64).
    pub text: Vec<u8>,
}

/// One `Piece` element.
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Piece {
    pub points: usize,
    pub cells: usize,
    pub point_data: Vec<ArraySpec>,
    pub cell_data: Vec<ArraySpec>,
    pub points_array: Option<ArraySpec>,
    /// The arrays of `<Cells>` (connectivity, offsets, types).
    pub cell_arrays: Vec<ArraySpec>,
    /// `NumberOfPolys` of a PolyData piece.
    pub polys: usize,
    /// The arrays of a PolyData `<Polys>` (connectivity, offsets).
    pub poly_arrays: Vec<ArraySpec>,
}

/// Encoding of the `AppendedData` section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Encoding {
    Raw,
    Base64,
}

/// The appended data region: bytes `start..end` of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Appended {
    pub encoding: Encoding,
    pub start: usize,
    pub end: usize,
}

/// The parsed structure of a VTK XML file.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Document {
    /// `type` on `VTKFile`: `PolyData`, `UnstructuredGrid`, ...
    pub data_type: String,
    pub byte_order: ByteOrder,
    pub header: HeaderType,
    /// `compressor` on `VTKFile`, when set.
    pub compressor: Option<String>,
    /// Dataset-level `FieldData` arrays.
    pub field_data: Vec<ArraySpec>,
    pub pieces: Vec<Piece>,
    pub appended: Option<Appended>,
    /// The offsets of all appended arrays, including those not kept (e.g.
    /// the cells of a PolyData), sorted: in base64 encoding each array's
    /// text ends where the next one starts.
    pub appended_offsets: Vec<usize>,
}

/// Where the `DataArray` being read goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dest {
    PointData,
    CellData,
    Points,
    Cells,
    Polys,
    FieldData,
    Ignored,
}

/// Position of the first occurrence of `needle` in `haystack`.
fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// Position of the last occurrence of `needle` in `haystack`.
fn rfind(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).rposition(|w| w == needle)
}

/// The attributes of a start tag as (name, value) strings.
fn attributes(reader: &Reader<&[u8]>, e: &BytesStart) -> Result<Vec<(String, String)>, String> {
    let mut out = Vec::new();
    // quick-xml's own duplicate check compares every attribute with every
    // earlier one (quadratic: 2·10⁵ attributes take minutes); a set does it
    // in one pass.
    let mut seen = std::collections::HashSet::new();
    for attr in e.attributes().with_checks(false) {
        let attr = attr.map_err(|err| format!("bad XML attribute: {err}"))?;
        if !seen.insert(attr.key.as_ref().to_vec()) {
            return Err(format!(
                "bad XML attribute: '{}' appears twice in one tag",
                String::from_utf8_lossy(attr.key.as_ref())
            ));
        }
        let key = String::from_utf8_lossy(attr.key.local_name().as_ref()).into_owned();
        let value = attr
            .decode_and_unescape_value(reader.decoder())
            .map_err(|err| format!("bad XML attribute '{key}': {err}"))?;
        out.push((key, value.trim().to_string()));
    }
    Ok(out)
}

fn get<'a>(attrs: &'a [(String, String)], key: &str) -> Option<&'a str> {
    attrs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

fn count_attr(attrs: &[(String, String)], key: &str, element: &str) -> Result<usize, String> {
    match get(attrs, key) {
        None => Ok(0),
        Some(v) => v
            .parse()
            .map_err(|_| format!("<{element}> has {key}=\"{v}\", which is not a count")),
    }
}

/// Parses the XML structure of a VTK XML file held in `bytes`.
pub(super) fn parse(bytes: &[u8]) -> Result<Document, String> {
    let appended_at = find(bytes, b"<AppendedData");
    let xml = &bytes[..appended_at.unwrap_or(bytes.len())];
    let mut reader = Reader::from_reader(xml);
    reader.config_mut().check_end_names = true;

    let mut doc: Option<Document> = None;
    let mut stack: Vec<String> = Vec::new();
    let mut current: Option<(Dest, ArraySpec)> = None;
    loop {
        let position = reader.buffer_position();
        let event = reader
            .read_event()
            .map_err(|e| format!("XML error near byte {position}: {e}"))?;
        match event {
            Event::Start(e) => {
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                let attrs = attributes(&reader, &e)?;
                open(&mut doc, &stack, &mut current, &name, &attrs)?;
                stack.push(name);
            }
            Event::Empty(e) => {
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                let attrs = attributes(&reader, &e)?;
                open(&mut doc, &stack, &mut current, &name, &attrs)?;
                stack.push(name);
                close(&mut doc, &mut stack, &mut current);
            }
            Event::End(_) => {
                close(&mut doc, &mut stack, &mut current);
            }
            Event::Text(t) => append_text(&stack, &mut current, t.as_ref()),
            Event::CData(t) => append_text(&stack, &mut current, t.as_ref()),
            Event::Eof => break,
            _ => {}
        }
    }
    let mut doc = doc.ok_or("not a VTK XML file: no <VTKFile> element")?;
    doc.appended_offsets.sort_unstable();
    doc.appended_offsets.dedup();
    match appended_at {
        // The XML before `<AppendedData` leaves only `<VTKFile>` open.
        Some(at) => {
            if stack.len() > 1 {
                return Err(format!(
                    "<AppendedData> appears inside <{}>",
                    stack.last().map_or("", String::as_str)
                ));
            }
            doc.appended = Some(appended_region(bytes, at)?);
        }
        None => {
            if let Some(open) = stack.last() {
                return Err(format!("the file ends inside <{open}> (truncated?)"));
            }
        }
    }
    Ok(doc)
}

/// Handles a start tag.
fn open(
    doc: &mut Option<Document>,
    stack: &[String],
    current: &mut Option<(Dest, ArraySpec)>,
    name: &str,
    attrs: &[(String, String)],
) -> Result<(), String> {
    let Some(doc) = doc else {
        if name != "VTKFile" {
            return Err(format!(
                "not a VTK XML file: the root element is <{name}>, not <VTKFile>"
            ));
        }
        *doc = Some(root(attrs)?);
        return Ok(());
    };
    let parent = stack.last().map(String::as_str).unwrap_or("");
    match name {
        "Piece" if stack.len() == 2 => {
            doc.pieces.push(Piece {
                points: count_attr(attrs, "NumberOfPoints", "Piece")?,
                cells: count_attr(attrs, "NumberOfCells", "Piece")?,
                polys: count_attr(attrs, "NumberOfPolys", "Piece")?,
                ..Piece::default()
            });
        }
        "DataArray" => {
            let in_piece = stack.len() == 4 && stack[2] == "Piece";
            let dest = match parent {
                "PointData" if in_piece => Dest::PointData,
                "CellData" if in_piece => Dest::CellData,
                "Points" if in_piece => Dest::Points,
                "Cells" if in_piece => Dest::Cells,
                "Polys" if in_piece => Dest::Polys,
                "FieldData" if stack.len() == 3 => Dest::FieldData,
                _ => Dest::Ignored,
            };
            let spec = data_array(attrs)?;
            if let Format::Appended(offset) = spec.format {
                doc.appended_offsets.push(offset);
            }
            *current = Some((dest, spec));
        }
        _ => {}
    }
    Ok(())
}

/// The attributes of the root `VTKFile` element.
fn root(attrs: &[(String, String)]) -> Result<Document, String> {
    let data_type = get(attrs, "type").unwrap_or("").to_string();
    let byte_order = match get(attrs, "byte_order") {
        None | Some("LittleEndian") => ByteOrder::Little,
        Some("BigEndian") => ByteOrder::Big,
        Some(other) => return Err(format!("unknown byte_order \"{other}\"")),
    };
    let header = match get(attrs, "header_type") {
        None | Some("UInt32") => HeaderType::U32,
        Some("UInt64") => HeaderType::U64,
        Some(other) => {
            return Err(format!(
                "unknown header_type \"{other}\" (expected UInt32 or UInt64)"
            ));
        }
    };
    let compressor = get(attrs, "compressor")
        .filter(|c| !c.is_empty())
        .map(str::to_string);
    Ok(Document {
        data_type,
        byte_order,
        header,
        compressor,
        field_data: Vec::new(),
        pieces: Vec::new(),
        appended: None,
        appended_offsets: Vec::new(),
    })
}

/// The attributes of a `DataArray` element.
fn data_array(attrs: &[(String, String)]) -> Result<ArraySpec, String> {
    let name = get(attrs, "Name").unwrap_or("").to_string();
    let label = if name.is_empty() {
        "<DataArray>".to_string()
    } else {
        format!("<DataArray Name=\"{name}\">")
    };
    let type_name = get(attrs, "type").unwrap_or("").to_string();
    let components = match get(attrs, "NumberOfComponents") {
        None => 1,
        Some(v) => v
            .parse::<usize>()
            .ok()
            .filter(|&c| c > 0)
            .ok_or_else(|| format!("{label} has NumberOfComponents=\"{v}\""))?,
    };
    let tuples = match get(attrs, "NumberOfTuples") {
        None => None,
        Some(v) => Some(
            v.parse::<usize>()
                .map_err(|_| format!("{label} has NumberOfTuples=\"{v}\""))?,
        ),
    };
    let format = match get(attrs, "format").unwrap_or("ascii") {
        "ascii" => Format::Ascii,
        "binary" => Format::Binary,
        "appended" => {
            let offset = get(attrs, "offset").unwrap_or("");
            Format::Appended(
                offset
                    .parse()
                    .map_err(|_| format!("{label} is appended but has offset=\"{offset}\""))?,
            )
        }
        other => return Err(format!("{label} has unknown format=\"{other}\"")),
    };
    Ok(ArraySpec {
        name,
        scalar: Scalar::parse(&type_name),
        type_name,
        components,
        tuples,
        format,
        text: Vec::new(),
    })
}

/// Handles an end tag (or the end of an empty element).
fn close(
    doc: &mut Option<Document>,
    stack: &mut Vec<String>,
    current: &mut Option<(Dest, ArraySpec)>,
) {
    let name = stack.pop();
    if name.as_deref() != Some("DataArray") {
        return;
    }
    let (Some(doc), Some((dest, spec))) = (doc.as_mut(), current.take()) else {
        return;
    };
    let piece = doc.pieces.last_mut();
    match (dest, piece) {
        (Dest::FieldData, _) => doc.field_data.push(spec),
        (Dest::PointData, Some(p)) => p.point_data.push(spec),
        (Dest::CellData, Some(p)) => p.cell_data.push(spec),
        (Dest::Points, Some(p)) if p.points_array.is_none() => p.points_array = Some(spec),
        (Dest::Cells, Some(p)) => p.cell_arrays.push(spec),
        (Dest::Polys, Some(p)) => p.poly_arrays.push(spec),
        _ => {}
    }
}

/// Adds text to the current `DataArray` if it is its direct content.
fn append_text(stack: &[String], current: &mut Option<(Dest, ArraySpec)>, text: &[u8]) {
    if stack.last().map(String::as_str) != Some("DataArray") {
        return;
    }
    if let Some((_, spec)) = current {
        spec.text.extend_from_slice(text);
    }
}

/// Parses the `AppendedData` start tag at `at` and locates the data after
/// its `_` marker.
fn appended_region(bytes: &[u8], at: usize) -> Result<Appended, String> {
    let rest = &bytes[at..];
    let gt = rest
        .iter()
        .position(|&b| b == b'>')
        .ok_or("the file ends inside the <AppendedData> tag")?;
    let mut reader = Reader::from_reader(&rest[..=gt]);
    let encoding = match reader.read_event() {
        Ok(Event::Start(e)) | Ok(Event::Empty(e)) => {
            let attrs = attributes(&reader, &e)?;
            match get(&attrs, "encoding").unwrap_or("raw") {
                "raw" => Encoding::Raw,
                "base64" => Encoding::Base64,
                other => return Err(format!("<AppendedData> has unknown encoding=\"{other}\"")),
            }
        }
        _ => return Err("malformed <AppendedData> tag".into()),
    };
    let after = at + gt + 1;
    let marker = bytes[after..]
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .map(|i| after + i)
        .filter(|&i| bytes[i] == b'_')
        .ok_or("<AppendedData> does not start with the '_' marker")?;
    let start = marker + 1;
    let mut end = rfind(&bytes[start..], b"</AppendedData>")
        .map(|i| start + i)
        .ok_or("the file ends inside <AppendedData> (truncated?)")?;
    if encoding == Encoding::Base64 {
        while end > start && bytes[end - 1].is_ascii_whitespace() {
            end -= 1;
        }
    }
    Ok(Appended {
        encoding,
        start,
        end,
    })
}

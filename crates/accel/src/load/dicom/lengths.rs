//! A walk over a DICOM file's element headers, before dicom-rs parses it: every defined length
//! must fit in the bytes left. dicom-parser (0.10) sizes a value's buffer from its declared
//! length and zero-fills it before reading (`stateful/decode.rs`), so one flipped length byte in
//! a 1 KB file made it allocate and clear up to 4 GB (seconds per file, or an abort under a
//! memory limit). This walk reads only headers, skipping values by seeking.
//!
//! Covered: the file meta group and data sets in explicit VR little or big endian and implicit
//! VR little endian, sequences and items of defined or undefined length, encapsulated pixel
//! data's fragments. A deflated data set is not walked (its bytes are compressed).

use std::io::{BufReader, Read, Seek};
use std::path::Path;

use crate::load::LoadError;

const IMPLICIT_LE: &str = "1.2.840.10008.1.2";
const EXPLICIT_BE: &str = "1.2.840.10008.1.2.2";
const UNDEFINED: u32 = 0xFFFF_FFFF;
/// Explicit VRs with a 2-byte length (PS3.5 7.1.2); every other VR, and one dicom-rs does not
/// know (read as UN), has 2 reserved bytes and a 4-byte length.
const SHORT_VRS: [&[u8; 2]; 21] = [
    b"AE", b"AS", b"AT", b"CS", b"DA", b"DS", b"DT", b"FL", b"FD", b"IS", b"LO", b"LT", b"PN", b"SH", b"SL", b"SS",
    b"ST", b"TM", b"UI", b"UL", b"US",
];

/// Bytes per value of the binary VRs dicom-rs reads as arrays (1 for the others). It reads
/// `length / size` values and leaves the rest: a length that is not a multiple misaligns its
/// parse, which then takes value bytes for the next header (and its length, up to 4 GB).
fn value_size(vr: &[u8; 2]) -> u32 {
    match vr {
        b"US" | b"SS" | b"OW" => 2,
        b"UL" | b"SL" | b"FL" | b"OF" | b"OL" | b"AT" => 4,
        b"FD" | b"OD" | b"SV" | b"UV" | b"OV" => 8,
        _ => 1,
    }
}

/// The VR the standard dictionary gives `tag` (what dicom-rs reads an implicit VR element as).
fn dictionary_vr(group: u16, element: u16) -> Option<[u8; 2]> {
    use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry, VirtualVr};
    match dicom_dictionary_std::StandardDataDictionary.by_tag(dicom_core::Tag(group, element))?.vr() {
        VirtualVr::Exact(vr) => Some(vr.to_bytes()),
        _ => None,
    }
}

struct Walk<R> {
    from: R,
    at: u64,
    len: u64,
}

/// What the walk found wrong: the tag, the byte offset of its header, what it claims.
type Problem = String;

impl<R: Read + Seek> Walk<R> {
    fn bytes<const N: usize>(&mut self) -> Result<Option<[u8; N]>, Problem> {
        if self.at + N as u64 > self.len {
            return Ok(None);
        }
        let mut b = [0u8; N];
        self.from.read_exact(&mut b).map_err(|e| e.to_string())?;
        self.at += N as u64;
        Ok(Some(b))
    }

    fn skip(&mut self, n: u64) -> Result<(), Problem> {
        self.from.seek_relative(n as i64).map_err(|e| e.to_string())?;
        self.at += n;
        Ok(())
    }

    /// Walks elements until `end` (a defined length's end), the end of the file, or a
    /// delimiter `stop` (item or sequence delimitation). `explicit`/`big` say the encoding.
    fn elements(&mut self, end: u64, explicit: bool, big: bool, depth: u32) -> Result<(), Problem> {
        if depth > 64 {
            return Err("sequences nested more than 64 deep".to_string());
        }
        let u16_of = |b: [u8; 2]| if big { u16::from_be_bytes(b) } else { u16::from_le_bytes(b) };
        let u32_of = |b: [u8; 4]| if big { u32::from_be_bytes(b) } else { u32::from_le_bytes(b) };
        while self.at < end {
            let start = self.at;
            let Some(tag) = self.bytes::<4>()? else { return Ok(()) };
            let (group, element) = (u16_of([tag[0], tag[1]]), u16_of([tag[2], tag[3]]));
            // Delimiters and items have no VR, in every encoding.
            if group == 0xFFFE {
                let Some(l) = self.bytes::<4>()? else { return Ok(()) };
                match element {
                    // A delimiter ends the item or sequence it closes; at the top level it
                    // closes nothing, and dicom-rs reads on past it, so the walk does too (a
                    // flipped length landing on one once hid a 4 GB length after it).
                    0xE00D | 0xE0DD if depth == 0 => continue,
                    0xE00D | 0xE0DD => return Ok(()),
                    _ => {
                        let l = u32_of(l);
                        if l == UNDEFINED {
                            self.elements(u64::MAX, explicit, big, depth + 1)?;
                        } else {
                            self.fits(start, (group, element), l)?;
                            let item_end = self.at + u64::from(l);
                            self.elements(item_end, explicit, big, depth + 1)?;
                            if self.at < item_end {
                                self.skip(item_end - self.at)?;
                            }
                        }
                        continue;
                    }
                }
            }
            let (vr, length) = if explicit {
                let Some(vr) = self.bytes::<2>()? else { return Ok(()) };
                if SHORT_VRS.contains(&&vr) {
                    let Some(l) = self.bytes::<2>()? else { return Ok(()) };
                    (Some(vr), u32::from(u16_of(l)))
                } else {
                    let Some(l) = self.bytes::<6>()? else { return Ok(()) };
                    (Some(vr), u32_of([l[2], l[3], l[4], l[5]]))
                }
            } else {
                let Some(l) = self.bytes::<4>()? else { return Ok(()) };
                (None, u32_of(l))
            };
            if length == UNDEFINED {
                if (group, element) == (0x7FE0, 0x0010) {
                    // Encapsulated pixel data: items holding fragments, then a delimiter.
                    self.fragments(big)?;
                    continue;
                }
                // Only sequences, UN and pixel data may have an undefined length (PS3.5 7.1);
                // dicom-rs reads any other element's 0xFFFFFFFF as a 4 GB length.
                let known = vr.or_else(|| dictionary_vr(group, element));
                let unknown = |v: [u8; 2]| v == *b"UN" || dicom_core::VR::from_binary(v).is_none();
                match known {
                    Some(v) if v == *b"SQ" => self.elements(u64::MAX, explicit, big, depth + 1)?,
                    // UN (or a VR dicom-rs does not know, read as UN): a sequence in implicit
                    // VR little endian (PS3.5 6.2.2).
                    Some(v) if unknown(v) => self.elements(u64::MAX, false, false, depth + 1)?,
                    None => self.elements(u64::MAX, explicit, big, depth + 1)?,
                    Some(v) => {
                        return Err(format!(
                            "element ({group:04X},{element:04X}) at byte {start} has VR {} and an undefined length, \
                             which only sequences and pixel data may have",
                            super::one_line(&String::from_utf8_lossy(&v))
                        ));
                    }
                }
                continue;
            }
            self.fits(start, (group, element), length)?;
            if let Some(v) = vr.or_else(|| dictionary_vr(group, element)) {
                let size = value_size(&v);
                if length % size != 0 {
                    return Err(format!(
                        "element ({group:04X},{element:04X}) at byte {start} has VR {} and length {length}, not a \
                         multiple of its {size}-byte values",
                        super::one_line(&String::from_utf8_lossy(&v))
                    ));
                }
            }
            if vr == Some(*b"SQ") {
                let seq_end = self.at + u64::from(length);
                self.elements(seq_end, explicit, big, depth + 1)?;
                if self.at < seq_end {
                    self.skip(seq_end - self.at)?;
                }
            } else {
                self.skip(u64::from(length))?;
            }
        }
        Ok(())
    }

    /// The fragments of encapsulated pixel data, each a defined-length item.
    fn fragments(&mut self, big: bool) -> Result<(), Problem> {
        loop {
            let start = self.at;
            let Some(tag) = self.bytes::<4>()? else { return Ok(()) };
            let Some(l) = self.bytes::<4>()? else { return Ok(()) };
            let u16_of = |b: [u8; 2]| if big { u16::from_be_bytes(b) } else { u16::from_le_bytes(b) };
            let (group, element) = (u16_of([tag[0], tag[1]]), u16_of([tag[2], tag[3]]));
            let l = if big { u32::from_be_bytes(l) } else { u32::from_le_bytes(l) };
            if group != 0xFFFE || element == 0xE0DD {
                return Ok(());
            }
            self.fits(start, (group, element), l)?;
            self.skip(u64::from(l))?;
        }
    }

    fn fits(&self, start: u64, (group, element): (u16, u16), length: u32) -> Result<(), Problem> {
        let left = self.len - self.at;
        if u64::from(length) > left {
            return Err(format!(
                "element ({group:04X},{element:04X}) at byte {start} claims {length} bytes, but only {left} follow"
            ));
        }
        Ok(())
    }
}

/// Fails when an element header of `path` (a file with the DICM magic at `magic_at`) claims
/// more bytes than the file holds after it.
pub fn check(path: &Path, magic_at: u64) -> Result<(), LoadError> {
    let read_error = |reason: String| LoadError::DicomRead { path: path.to_path_buf(), reason };
    let file = std::fs::File::open(path).map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?;
    let len = file.metadata().map_err(|source| LoadError::Io { path: path.to_path_buf(), source })?.len();
    let mut walk = Walk { from: BufReader::new(file), at: 0, len };
    walk.skip(magic_at + 4).map_err(read_error)?;
    // The meta group: explicit VR little endian, (0002,0000) gives its length; read its
    // elements to find the transfer syntax.
    let mut transfer_syntax = String::new();
    while walk.at + 8 <= len {
        let start = walk.at;
        let Some(tag) = walk.bytes::<4>().map_err(read_error)? else { break };
        if u16::from_le_bytes([tag[0], tag[1]]) != 0x0002 {
            walk.from.seek_relative(-4).map_err(|e| read_error(e.to_string()))?;
            walk.at -= 4;
            break;
        }
        let element = u16::from_le_bytes([tag[2], tag[3]]);
        let Some(vr) = walk.bytes::<2>().map_err(read_error)? else { break };
        let length = if SHORT_VRS.contains(&&vr) {
            let Some(l) = walk.bytes::<2>().map_err(read_error)? else { break };
            u32::from(u16::from_le_bytes(l))
        } else {
            let Some(l) = walk.bytes::<6>().map_err(read_error)? else { break };
            u32::from_le_bytes([l[2], l[3], l[4], l[5]])
        };
        walk.fits(start, (0x0002, element), length).map_err(read_error)?;
        if element == 0x0010 && length <= 64 {
            let mut uid = vec![0u8; length as usize];
            walk.from.read_exact(&mut uid).map_err(|e| read_error(e.to_string()))?;
            walk.at += u64::from(length);
            transfer_syntax = String::from_utf8_lossy(&uid).trim_end_matches(['\0', ' ']).to_string();
        } else {
            walk.skip(u64::from(length)).map_err(read_error)?;
        }
    }
    let (explicit, big) = match transfer_syntax.as_str() {
        IMPLICIT_LE => (false, false),
        EXPLICIT_BE => (true, true),
        // Deflated data sets are compressed: nothing to walk.
        "1.2.840.10008.1.2.1.99" => return Ok(()),
        _ => (true, false),
    };
    walk.elements(u64::MAX, explicit, big, 0)
        .map_err(|problem| read_error(format!("{problem}: a length field is corrupt")))
}

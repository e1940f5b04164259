//! A minimal ZIP writer: stored (uncompressed) entries, which every FMI importer reads. The workspace has no ZIP
//! crate, and an FMU holds two or three files whose compression would save little next to the build's time.

/// An archive in memory: add files, then take the bytes.
#[derive(Default)]
pub struct ZipWriter {
    out: Vec<u8>,
    central: Vec<u8>,
    entries: u16,
}

/// Why a file cannot go into the archive.
#[derive(Debug, thiserror::Error)]
pub enum ZipError {
    #[error("`{0}` is too large for a ZIP archive without the ZIP64 extension (4 GiB)")]
    TooLarge(String),
    #[error("too many files for one ZIP archive")]
    TooMany,
}

impl ZipWriter {
    pub fn new() -> ZipWriter {
        ZipWriter::default()
    }

    /// Adds `data` as the file `name` (`/` between directories).
    pub fn add(&mut self, name: &str, data: &[u8]) -> Result<(), ZipError> {
        let too_large = || ZipError::TooLarge(name.to_string());
        let size = u32::try_from(data.len()).map_err(|_| too_large())?;
        let offset = u32::try_from(self.out.len()).map_err(|_| too_large())?;
        let name_len = u16::try_from(name.len()).map_err(|_| too_large())?;
        self.entries = self.entries.checked_add(1).ok_or(ZipError::TooMany)?;
        let crc = crc32(data);
        // Local file header: version 2.0, no flags, stored, a fixed date (1980-01-01) so that the bytes depend
        // only on the contents.
        let common = |v: &mut Vec<u8>| {
            put16(v, 0);
            put16(v, 0);
            put16(v, 0);
            put16(v, 0x21);
            put32(v, crc);
            put32(v, size);
            put32(v, size);
            put16(v, name_len);
            put16(v, 0);
        };
        put32(&mut self.out, 0x0403_4b50);
        put16(&mut self.out, 20);
        common(&mut self.out);
        self.out.extend_from_slice(name.as_bytes());
        self.out.extend_from_slice(data);
        // Central directory entry: made by version 2.0 on Unix, regular file rw-r--r--.
        put32(&mut self.central, 0x0201_4b50);
        put16(&mut self.central, 0x0314);
        put16(&mut self.central, 20);
        common(&mut self.central);
        put16(&mut self.central, 0);
        put16(&mut self.central, 0);
        put16(&mut self.central, 0);
        put32(&mut self.central, 0o100644 << 16);
        put32(&mut self.central, offset);
        self.central.extend_from_slice(name.as_bytes());
        Ok(())
    }

    /// The archive: the entries, the central directory and its end record.
    pub fn finish(mut self) -> Result<Vec<u8>, ZipError> {
        let too_large = || ZipError::TooLarge("the archive".into());
        let start = u32::try_from(self.out.len()).map_err(|_| too_large())?;
        let size = u32::try_from(self.central.len()).map_err(|_| too_large())?;
        self.out.append(&mut self.central);
        put32(&mut self.out, 0x0605_4b50);
        put16(&mut self.out, 0);
        put16(&mut self.out, 0);
        put16(&mut self.out, self.entries);
        put16(&mut self.out, self.entries);
        put32(&mut self.out, size);
        put32(&mut self.out, start);
        put16(&mut self.out, 0);
        Ok(self.out)
    }
}

fn put16(v: &mut Vec<u8>, x: u16) {
    v.extend_from_slice(&x.to_le_bytes());
}

fn put32(v: &mut Vec<u8>, x: u32) {
    v.extend_from_slice(&x.to_le_bytes());
}

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), as ZIP requires.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_check_value() {
        // The check value of CRC-32/ISO-HDLC (the catalogue of Greg Cook's "CRC RevEng").
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn archive_layout() {
        let mut z = ZipWriter::new();
        z.add("a.txt", b"hello").unwrap();
        let bytes = z.finish().unwrap();
        // Local header (30 + 5 name + 5 data), central entry (46 + 5), end record (22).
        assert_eq!(bytes.len(), 40 + 51 + 22);
        assert_eq!(&bytes[..4], b"PK\x03\x04");
        assert_eq!(&bytes[35..40], b"hello");
        assert_eq!(&bytes[bytes.len() - 22..bytes.len() - 18], b"PK\x05\x06");
    }
}

//! ELF section headers of the firmware images: flash and static RAM, and the `.stack_sizes`
//! section.

use std::collections::HashMap;

use anyhow::{Result, anyhow, bail};

use super::RAM_ORIGIN;

/// A section header.
#[derive(Debug, Clone)]
pub(super) struct Section {
    name: String,
    kind: u32,
    flags: u32,
    addr: u64,
    offset: u64,
    size: u64,
}

const SHT_NOBITS: u32 = 8;
const SHF_ALLOC: u32 = 2;

fn le32(b: &[u8], at: usize) -> Result<u32> {
    let s = b.get(at..at + 4).ok_or_else(|| anyhow!("ELF truncated"))?;
    Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

fn le16(b: &[u8], at: usize) -> Result<u16> {
    let s = b.get(at..at + 2).ok_or_else(|| anyhow!("ELF truncated"))?;
    Ok(u16::from_le_bytes([s[0], s[1]]))
}

/// The section headers of a 32-bit little-endian ELF.
pub(super) fn sections(elf: &[u8]) -> Result<Vec<Section>> {
    if elf.get(..6) != Some(&[0x7f, b'E', b'L', b'F', 1, 1][..]) {
        bail!("not a 32-bit little-endian ELF");
    }
    let shoff = le32(elf, 0x20)? as usize;
    let shentsize = usize::from(le16(elf, 0x2e)?);
    let shnum = usize::from(le16(elf, 0x30)?);
    let shstrndx = usize::from(le16(elf, 0x32)?);
    let mut raw = Vec::with_capacity(shnum);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        raw.push((
            le32(elf, h)?,
            le32(elf, h + 4)?,
            le32(elf, h + 8)?,
            le32(elf, h + 12)?,
            le32(elf, h + 16)?,
            le32(elf, h + 20)?,
        ));
    }
    let strtab = raw.get(shstrndx).map_or(0, |s| s.4 as usize);
    raw.into_iter()
        .map(|(name, kind, flags, addr, offset, size)| {
            let start = strtab + name as usize;
            let bytes = elf.get(start..).unwrap_or_default();
            let end = bytes.iter().position(|&c| c == 0).unwrap_or(0);
            Ok(Section {
                name: String::from_utf8_lossy(bytes.get(..end).unwrap_or_default()).into_owned(),
                kind,
                flags,
                addr: u64::from(addr),
                offset: u64::from(offset),
                size: u64::from(size),
            })
        })
        .collect()
}

/// Flash and static RAM of an image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryUse {
    /// Bytes stored in flash: every allocated section with contents (`.vector_table`,
    /// `.text`, `.rodata`, and `.data`'s initial values).
    pub flash_bytes: u64,
    /// Bytes of RAM taken by statics (`.data`, `.bss`, `.uninit`).
    pub static_ram_bytes: u64,
}

/// Flash and static RAM from the section headers.
pub(super) fn memory_use(secs: &[Section]) -> MemoryUse {
    let alloc = secs.iter().filter(|s| s.flags & SHF_ALLOC != 0);
    MemoryUse {
        flash_bytes: alloc.clone().filter(|s| s.kind != SHT_NOBITS).map(|s| s.size).sum(),
        static_ram_bytes: alloc.filter(|s| s.addr >= RAM_ORIGIN).map(|s| s.size).sum(),
    }
}

/// The `.stack_sizes` section (`-Z emit-stack-sizes`): function address (Thumb bit cleared) →
/// frame bytes. `None` if the image has no such section.
pub(super) fn stack_sizes(elf: &[u8], secs: &[Section]) -> Option<HashMap<u32, u32>> {
    let s = secs.iter().find(|s| s.name == ".stack_sizes")?;
    let data = elf.get(s.offset as usize..(s.offset + s.size) as usize)?;
    let mut out = HashMap::new();
    let mut i = 0;
    while i + 4 <= data.len() {
        let addr = le32(data, i).ok()? & !1;
        i += 4;
        let (mut size, mut shift) = (0u32, 0);
        loop {
            let b = *data.get(i)?;
            i += 1;
            size |= u32::from(b & 0x7f) << shift;
            shift += 7;
            if b & 0x80 == 0 {
                break;
            }
        }
        out.insert(addr, size);
    }
    Some(out)
}

/// The bytes an image puts in flash (allocated sections with contents below RAM), for reading
/// literal-pool words and telling flash addresses from RAM ones.
#[derive(Debug, Clone, Default)]
pub(super) struct FlashImage {
    /// `(address, size, file offset)` of each flash section.
    ranges: Vec<(u64, u64, u64)>,
    /// The ELF file.
    bytes: Vec<u8>,
}

impl FlashImage {
    /// The flash sections of `elf`.
    pub(super) fn new(elf: Vec<u8>) -> Result<Self> {
        let ranges = sections(&elf)?
            .iter()
            .filter(|s| s.flags & SHF_ALLOC != 0 && s.kind != SHT_NOBITS && s.addr < RAM_ORIGIN && s.size > 0)
            .map(|s| (s.addr, s.size, s.offset))
            .collect();
        Ok(Self { ranges, bytes: elf })
    }

    /// Whether `addr` lies in flash.
    pub(super) fn contains(&self, addr: u32) -> bool {
        let a = u64::from(addr);
        self.ranges.iter().any(|&(start, size, _)| a >= start && a < start + size)
    }

    /// A flash range without file contents (tests).
    #[cfg(test)]
    pub(super) fn set_test_range(&mut self, addr: u64, size: u64) {
        self.ranges.push((addr, size, 0));
    }

    /// The little-endian word stored at flash address `addr`.
    pub(super) fn word(&self, addr: u32) -> Option<u32> {
        let a = u64::from(addr);
        let &(start, _, off) = self.ranges.iter().find(|&&(s, z, _)| a >= s && a + 4 <= s + z)?;
        le32(&self.bytes, usize::try_from(off + a - start).ok()?).ok()
    }
}

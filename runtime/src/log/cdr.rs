//! CDR (little-endian, the ROS 2 encoding of every channel's messages): the encoder the
//! recorder writes with and the reader that decodes a message field by field.

/// CDR (little-endian) encoding into a reused buffer: every primitive aligned to its size,
/// counted from after the 4-byte encapsulation header.
pub struct Cdr {
    pub buf: Vec<u8>,
}

impl Cdr {
    #[inline]
    pub(super) fn start(&mut self) {
        self.buf.clear();
        self.buf.extend_from_slice(&[0, 1, 0, 0]);
    }
    #[inline]
    pub(super) fn align(&mut self, n: usize) {
        while !(self.buf.len() - 4).is_multiple_of(n) {
            self.buf.push(0);
        }
    }
    #[inline]
    pub(super) fn f64(&mut self, x: f64) {
        self.align(8);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    #[inline]
    pub(super) fn i32(&mut self, x: i32) {
        self.align(4);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    #[inline]
    pub(super) fn u32(&mut self, x: u32) {
        self.align(4);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    #[inline]
    pub(super) fn u64(&mut self, x: u64) {
        self.align(8);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    #[inline]
    pub(super) fn u16(&mut self, x: u16) {
        self.align(2);
        self.buf.extend_from_slice(&x.to_le_bytes());
    }
    #[inline]
    pub(super) fn bool(&mut self, x: bool) {
        self.buf.push(x as u8);
    }
    #[inline]
    pub(super) fn string(&mut self, text: &str) {
        self.u32(text.len() as u32 + 1);
        self.buf.extend_from_slice(text.as_bytes());
        self.buf.push(0);
    }
    #[inline]
    pub(super) fn f32s(&mut self, values: impl ExactSizeIterator<Item = f64>) {
        self.u32(values.len() as u32);
        for x in values {
            self.buf.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    #[inline]
    pub(super) fn u16s(&mut self, values: &[u16]) {
        self.u32(values.len() as u32);
        for &x in values {
            self.u16(x);
        }
    }
}

/// Reads CDR written by [`Cdr`], field by field.
pub struct CdrReader<'a> {
    data: &'a [u8],
    at: usize,
}

/// A CDR message too short for its schema.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("a message is shorter than its schema")]
pub struct ShortMessage;

impl<'a> CdrReader<'a> {
    pub fn new(data: &'a [u8]) -> CdrReader<'a> {
        CdrReader { data, at: 4 }
    }
    #[inline]
    fn align(&mut self, n: usize) {
        while !(self.at - 4).is_multiple_of(n) {
            self.at += 1;
        }
    }
    #[inline]
    fn take(&mut self, n: usize) -> Result<&'a [u8], ShortMessage> {
        let bytes = self.data.get(self.at..self.at + n).ok_or(ShortMessage)?;
        self.at += n;
        Ok(bytes)
    }
    pub fn f64(&mut self) -> Result<f64, ShortMessage> {
        self.align(8);
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    pub fn i32(&mut self) -> Result<i32, ShortMessage> {
        self.align(4);
        Ok(i32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub fn u32(&mut self) -> Result<u32, ShortMessage> {
        self.align(4);
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub fn u64(&mut self) -> Result<u64, ShortMessage> {
        self.align(8);
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    pub fn u16(&mut self) -> Result<u16, ShortMessage> {
        self.align(2);
        Ok(u16::from_le_bytes(
            self.take(2)?.try_into().expect("2 bytes"),
        ))
    }
    pub fn bool(&mut self) -> Result<bool, ShortMessage> {
        Ok(self.take(1)?[0] != 0)
    }
    pub fn string(&mut self) -> Result<String, ShortMessage> {
        let length = self.u32()? as usize;
        let bytes = self.take(length)?;
        Ok(String::from_utf8_lossy(bytes.strip_suffix(&[0]).unwrap_or(bytes)).into_owned())
    }
    pub fn f32s(&mut self) -> Result<Vec<f32>, ShortMessage> {
        let n = self.u32()? as usize;
        if n > self.data.len() {
            return Err(ShortMessage);
        }
        (0..n)
            .map(|_| {
                Ok(f32::from_le_bytes(
                    self.take(4)?.try_into().expect("4 bytes"),
                ))
            })
            .collect()
    }
    pub fn u16s(&mut self, fixed: Option<usize>) -> Result<Vec<u16>, ShortMessage> {
        let n = match fixed {
            Some(n) => n,
            None => self.u32()? as usize,
        };
        if n > self.data.len() {
            return Err(ShortMessage);
        }
        (0..n).map(|_| self.u16()).collect()
    }
    pub fn strings(&mut self) -> Result<Vec<String>, ShortMessage> {
        let n = self.u32()? as usize;
        if n > self.data.len() {
            return Err(ShortMessage);
        }
        (0..n).map(|_| self.string()).collect()
    }
}

//! The protocol-buffer wire format, as far as an ONNX model needs it
//! (<https://protobuf.dev/programming-guides/encoding/>): varints,
//! length-delimited fields (strings, bytes, nested messages) and
//! little-endian `float`/`double` payloads inside `raw_data`.

/// A message being written: fields appended in the order the caller
/// gives them.
#[derive(Debug, Default, Clone)]
pub struct Message {
    bytes: Vec<u8>,
}

/// Wire type of varint fields (`int32`, `int64`, enums).
const VARINT: u64 = 0;
/// Wire type of length-delimited fields (strings, bytes, messages).
const LENGTH_DELIMITED: u64 = 2;

fn push_varint(out: &mut Vec<u8>, mut value: u64) {
    while value >= 0x80 {
        out.push((value as u8 & 0x7f) | 0x80);
        value >>= 7;
    }
    out.push(value as u8);
}

impl Message {
    /// An empty message.
    pub fn new() -> Self {
        Self::default()
    }

    fn key(&mut self, field: u32, wire_type: u64) {
        push_varint(&mut self.bytes, (u64::from(field) << 3) | wire_type);
    }

    /// An `int64`/`int32` field (non-negative values only: ONNX's sizes,
    /// versions and enums).
    pub fn int(mut self, field: u32, value: u64) -> Self {
        self.key(field, VARINT);
        push_varint(&mut self.bytes, value);
        self
    }

    /// A `bytes` field.
    pub fn bytes(mut self, field: u32, value: &[u8]) -> Self {
        self.key(field, LENGTH_DELIMITED);
        push_varint(&mut self.bytes, value.len() as u64);
        self.bytes.extend_from_slice(value);
        self
    }

    /// A `string` field.
    pub fn string(self, field: u32, value: &str) -> Self {
        self.bytes(field, value.as_bytes())
    }

    /// A nested message field.
    pub fn message(self, field: u32, value: &Message) -> Self {
        self.bytes(field, &value.bytes)
    }

    /// The encoded message.
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_encode_as_the_protobuf_guide_shows() {
        // the guide's examples: field 1 = 150 is 08 96 01; field 2 =
        // "testing" is 12 07 74 65 73 74 69 6e 67
        assert_eq!(Message::new().int(1, 150).into_bytes(), [0x08, 0x96, 0x01]);
        assert_eq!(
            Message::new().string(2, "testing").into_bytes(),
            [0x12, 0x07, 0x74, 0x65, 0x73, 0x74, 0x69, 0x6e, 0x67]
        );
        // a nested message is its bytes, length-delimited
        let inner = Message::new().int(1, 150);
        assert_eq!(
            Message::new().message(3, &inner).into_bytes(),
            [0x1a, 0x03, 0x08, 0x96, 0x01]
        );
        // a varint of 2^63 takes ten bytes
        let big = Message::new().int(1, 1 << 63).into_bytes();
        assert_eq!(big.len(), 11);
        assert_eq!(*big.last().unwrap(), 0x01);
    }
}

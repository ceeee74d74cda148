//! TI Z-Stack Monitor-and-Test frames (the UNPI transport of ZNP firmware) and the one command
//! the bridge reads from them, `AF_INCOMING_MSG`.
//!
//! Layout: `0xFE | LEN | CMD0 | CMD1 | DATA[LEN] | FCS`, CMD0 = type << 5 | subsystem, FCS =
//! XOR of LEN, CMD0, CMD1 and DATA. Multi-byte fields are little-endian.

// Frames are read and written at the field table's offsets once their length is checked.
#![allow(clippy::indexing_slicing)]

use crate::nmea::xor;

/// Start of frame of an MT frame.
pub const MT_SOF: u8 = 0xFE;

/// CMD0 of `AF_INCOMING_MSG`: type AREQ (2), subsystem AF (4).
pub const AF_INCOMING_MSG_CMD0: u8 = 0x44;
/// CMD1 of `AF_INCOMING_MSG`.
pub const AF_INCOMING_MSG_CMD1: u8 = 0x81;
/// Bytes of `AF_INCOMING_MSG` before its application data.
pub const AF_HEADER: usize = field::DATA;

/// Where each field of `AF_INCOMING_MSG` sits in the frame's data: the one table that parse
/// and encode both read (smoltcp's `mod field`).
mod field {
    use core::ops::Range;
    pub const GROUP_ID: Range<usize> = 0..2;
    pub const CLUSTER_ID: Range<usize> = 2..4;
    pub const SRC_ADDR: Range<usize> = 4..6;
    pub const SRC_ENDPOINT: usize = 6;
    pub const DST_ENDPOINT: usize = 7;
    pub const WAS_BROADCAST: usize = 8;
    pub const LINK_QUALITY: usize = 9;
    pub const SECURITY_USE: usize = 10;
    pub const TIMESTAMP: Range<usize> = 11..15;
    pub const TRANS_SEQ: usize = 15;
    pub const LEN: usize = 16;
    pub const DATA: usize = 17;
}

/// Why an MT frame gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MtError {
    /// Another command (valid frame, not one the bridge reads).
    Unsupported,
    /// The data is shorter than the command's fields say.
    Short,
    /// The output buffer cannot hold the encoded frame, or the data exceeds 255 bytes.
    TooLong,
}

/// Command type, the top three bits of CMD0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandType {
    /// 0: poll.
    Poll,
    /// 1: synchronous request.
    Sreq,
    /// 2: asynchronous request or indication.
    Areq,
    /// 3: synchronous response.
    Srsp,
    /// 4-7: reserved.
    Reserved(u8),
}

/// A Monitor-and-Test frame: command bytes and data (SOF, LEN and FCS stripped).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MtFrame<'a> {
    /// Type (bits 7-5) and subsystem (bits 4-0).
    pub cmd0: u8,
    /// Command id within the subsystem.
    pub cmd1: u8,
    /// Payload, LEN bytes.
    pub data: &'a [u8],
}

impl MtFrame<'_> {
    /// The command type.
    pub fn command_type(&self) -> CommandType {
        match self.cmd0 >> 5 {
            0 => CommandType::Poll,
            1 => CommandType::Sreq,
            2 => CommandType::Areq,
            3 => CommandType::Srsp,
            t => CommandType::Reserved(t),
        }
    }

    /// The subsystem, the low five bits of CMD0 (4 = AF, 5 = ZDO, ...).
    pub fn subsystem(&self) -> u8 {
        self.cmd0 & 0x1f
    }

    /// Encode into `out`; returns the frame's length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, MtError> {
        let len = u8::try_from(self.data.len()).map_err(|_| MtError::TooLong)?;
        let total = self.data.len() + 5;
        if out.len() < total {
            return Err(MtError::TooLong);
        }
        out[0] = MT_SOF;
        out[1] = len;
        out[2] = self.cmd0;
        out[3] = self.cmd1;
        out[4..4 + self.data.len()].copy_from_slice(self.data);
        out[total - 1] = xor(&out[1..total - 1]);
        Ok(total)
    }
}

/// `AF_INCOMING_MSG`: a packet the coordinator heard, with its link quality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AfIncomingMsg<'a> {
    /// Group id (0 if none).
    pub group_id: u16,
    /// Cluster id.
    pub cluster_id: u16,
    /// Short address of the sender: names the anchor.
    pub src_addr: u16,
    /// Source endpoint.
    pub src_endpoint: u8,
    /// Destination endpoint.
    pub dst_endpoint: u8,
    /// Whether the packet was a broadcast.
    pub was_broadcast: bool,
    /// Link quality indicator, 0-255.
    pub link_quality: u8,
    /// Whether the packet was secured.
    pub security_use: bool,
    /// The receiver's timestamp (MAC timer ticks).
    pub timestamp: u32,
    /// Transaction sequence number.
    pub trans_seq: u8,
    /// Application data.
    pub data: &'a [u8],
}

fn u16_at(d: &[u8], r: core::ops::Range<usize>) -> u16 {
    u16::from_le_bytes([d[r.start], d[r.start + 1]])
}

impl<'a> AfIncomingMsg<'a> {
    /// Decode an MT frame. Other commands are [`MtError::Unsupported`]; bytes after the
    /// application data (some firmware appends the MAC source address) are ignored.
    pub fn parse(frame: &MtFrame<'a>) -> Result<Self, MtError> {
        if (frame.cmd0, frame.cmd1) != (AF_INCOMING_MSG_CMD0, AF_INCOMING_MSG_CMD1) {
            return Err(MtError::Unsupported);
        }
        let d = frame.data;
        if d.len() < AF_HEADER {
            return Err(MtError::Short);
        }
        let len = d[field::LEN] as usize;
        let data = d.get(AF_HEADER..AF_HEADER + len).ok_or(MtError::Short)?;
        let t = field::TIMESTAMP.start;
        Ok(Self {
            group_id: u16_at(d, field::GROUP_ID),
            cluster_id: u16_at(d, field::CLUSTER_ID),
            src_addr: u16_at(d, field::SRC_ADDR),
            src_endpoint: d[field::SRC_ENDPOINT],
            dst_endpoint: d[field::DST_ENDPOINT],
            was_broadcast: d[field::WAS_BROADCAST] != 0,
            link_quality: d[field::LINK_QUALITY],
            security_use: d[field::SECURITY_USE] != 0,
            timestamp: u32::from_le_bytes([d[t], d[t + 1], d[t + 2], d[t + 3]]),
            trans_seq: d[field::TRANS_SEQ],
            data,
        })
    }

    /// Write the frame's data (header and application data) into `out`; returns its length.
    pub fn encode_data(&self, out: &mut [u8]) -> Result<usize, MtError> {
        let len = u8::try_from(self.data.len()).map_err(|_| MtError::TooLong)?;
        let total = AF_HEADER + self.data.len();
        if total > 255 || out.len() < total {
            return Err(MtError::TooLong);
        }
        out[field::GROUP_ID].copy_from_slice(&self.group_id.to_le_bytes());
        out[field::CLUSTER_ID].copy_from_slice(&self.cluster_id.to_le_bytes());
        out[field::SRC_ADDR].copy_from_slice(&self.src_addr.to_le_bytes());
        out[field::SRC_ENDPOINT] = self.src_endpoint;
        out[field::DST_ENDPOINT] = self.dst_endpoint;
        out[field::WAS_BROADCAST] = u8::from(self.was_broadcast);
        out[field::LINK_QUALITY] = self.link_quality;
        out[field::SECURITY_USE] = u8::from(self.security_use);
        out[field::TIMESTAMP].copy_from_slice(&self.timestamp.to_le_bytes());
        out[field::TRANS_SEQ] = self.trans_seq;
        out[field::LEN] = len;
        out[AF_HEADER..total].copy_from_slice(self.data);
        Ok(total)
    }

    /// Encode as a whole MT frame into `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, MtError> {
        let mut data = [0u8; 255];
        let n = self.encode_data(&mut data)?;
        MtFrame {
            cmd0: AF_INCOMING_MSG_CMD0,
            cmd1: AF_INCOMING_MSG_CMD1,
            data: &data[..n],
        }
        .encode(out)
    }
}

/// Link quality to RSSI: `dbm = offset + slope * lqi`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkQualityMap {
    /// dBm per LQI step.
    pub slope: f32,
    /// dBm at LQI 0.
    pub offset: f32,
}

impl Default for LinkQualityMap {
    /// TI's CC2530 MAC: LQI 0 is -97 dBm, 255 is +10 dBm, linear between.
    fn default() -> Self {
        Self {
            slope: 107.0 / 255.0,
            offset: -97.0,
        }
    }
}

impl LinkQualityMap {
    /// RSSI in dBm of a link quality.
    pub fn rssi_dbm(&self, link_quality: u8) -> f32 {
        self.offset + self.slope * f32::from(link_quality)
    }

    /// The link quality whose RSSI is nearest `dbm` (for simulated captures).
    pub fn link_quality(&self, dbm: f32) -> u8 {
        let q = libm::roundf((dbm - self.offset) / self.slope);
        if q.is_nan() {
            0
        } else {
            q.clamp(0.0, 255.0) as u8
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{Demux, Frame};

    #[test]
    fn ti_layout_round_trip() {
        let msg = AfIncomingMsg {
            group_id: 0,
            cluster_id: 0x0006,
            src_addr: 0x1a2b,
            src_endpoint: 1,
            dst_endpoint: 1,
            was_broadcast: false,
            link_quality: 0x96,
            security_use: false,
            timestamp: 0x0012_3456,
            trans_seq: 7,
            data: &[0xFE, 0xFE, 0xFE],
        };
        let mut buf = [0u8; 300];
        let n = msg.encode(&mut buf).expect("fits");
        assert_eq!(n, 5 + 17 + 3);
        // SOF, LEN, CMD0 = AREQ << 5 | AF, CMD1, srcaddr little-endian at data offset 4.
        assert_eq!(&buf[..4], &[0xFE, 20, 0x44, 0x81]);
        assert_eq!(&buf[8..10], &[0x2b, 0x1a]);
        let fcs = buf[1..n - 1].iter().fold(0, |x, b| x ^ b);
        assert_eq!(buf[n - 1], fcs);
        let mut d = Demux::<600>::new();
        let mut got = None;
        let mut sink = |f: Frame<'_>| {
            if let Frame::Mt(m) = f {
                assert_eq!(m.command_type(), CommandType::Areq);
                assert_eq!(m.subsystem(), 4);
                got = AfIncomingMsg::parse(&m)
                    .ok()
                    .map(|a| (a.src_addr, a.link_quality, a.timestamp));
            }
        };
        // The 0xFE bytes of the payload might start an inner frame: it waits for the end.
        d.feed(&buf[..n], &mut sink);
        d.finish_into(&mut sink);
        assert_eq!(got, Some((0x1a2b, 0x96, 0x0012_3456)));
    }

    #[test]
    fn link_quality_map() {
        let m = LinkQualityMap::default();
        assert_eq!(m.rssi_dbm(0), -97.0);
        assert!((m.rssi_dbm(255) - 10.0).abs() < 1e-5);
        assert_eq!(m.link_quality(m.rssi_dbm(100)), 100);
        assert_eq!(m.link_quality(f32::NAN), 0);
    }
}

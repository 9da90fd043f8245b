//! The pre-scan: makes the bytes safe for `hidreport` and corrects its Maximum
//! signedness (see the [hid module docs](crate::input::hid)), with `hidreport`'s own
//! item tokenizer.

use super::layout::NotTouch;
use hidreport::hid::{GlobalItem, Item, ItemType, LocalItem, MainItem, ReportDescriptorItems};

/// Most bytes in a report descriptor (the kernel's `HID_MAX_DESCRIPTOR_SIZE`).
pub const MAX_DESCRIPTOR_BYTES: usize = 4096;
/// Largest Report Size (bits) a data item may use (the kernel's limit).
pub const MAX_REPORT_SIZE_BITS: u64 = 256;
/// Largest Report Count a data item may use (the kernel's `HID_MAX_USAGES`).
pub const MAX_REPORT_COUNT: u64 = 12_288;
/// Most usages one Usage Minimum/Maximum pair may expand to.
const MAX_USAGE_RANGE: u64 = 65_536;
/// Most data bits all items of a descriptor may declare together.
const MAX_TOTAL_BITS: u64 = 1 << 24;
/// Rough bound on the memory `hidreport` may use for one descriptor, in bytes.
const MAX_PARSE_COST_BYTES: u64 = 64 << 20;

/// The descriptor as handed to `hidreport`, with a map back to original offsets.
pub(super) struct Normalised {
    pub(super) bytes: Vec<u8>,
    /// `(first normalised offset, bytes inserted before it)`, increasing.
    pub(super) shifts: Vec<(usize, usize)>,
}

impl Normalised {
    pub(super) fn original_offset(&self, off: usize) -> usize {
        let shift = self
            .shifts
            .iter()
            .rev()
            .find(|(start, _)| *start <= off)
            .map_or(0, |(_, s)| *s);
        off.saturating_sub(shift)
    }
}

/// hidreport's global state, as far as the pre-scan needs it.
#[derive(Copy, Clone, Default)]
struct ScanGlobals {
    logical_min_negative: bool,
    physical_min_negative: bool,
    report_size: u64,
    report_count: u64,
}

/// hidreport's local state, as far as the pre-scan needs it.
#[derive(Copy, Clone, Default)]
struct ScanLocals {
    usages: u64,
    usage_min: Option<u32>,
    usage_max: Option<u32>,
}

impl ScanLocals {
    /// Usages hidreport's `compile_usages` would create.
    fn compiled(&self) -> u64 {
        match (self.usage_min, self.usage_max) {
            (Some(min), Some(max)) if max >= min => u64::from(max - min) + 1,
            (Some(_), _) => 0,
            (None, _) => self.usages,
        }
    }
}

/// Widens a Logical/Physical Maximum item whose data hidreport would sign-extend
/// but the kernel reads unsigned. Returns the replacement bytes.
fn widen_maximum(item: &[u8]) -> Option<Vec<u8>> {
    let data = item.get(1..)?;
    let top_set = data.last().is_some_and(|b| b & 0x80 != 0);
    let (code, width) = match data.len() {
        1 => (2u8, 2usize),
        2 => (3, 4),
        _ => return None,
    };
    if !top_set {
        return None;
    }
    let mut out = Vec::with_capacity(1 + width);
    out.push((item[0] & 0xFC) | code);
    out.extend_from_slice(data);
    out.resize(1 + width, 0);
    Some(out)
}

/// Checks a descriptor against the kernel's limits and `hidreport`'s weak spots,
/// and returns the bytes to parse (see the [module docs](crate::input::hid)).
pub(super) fn normalise(desc: &[u8]) -> Result<Normalised, NotTouch> {
    if desc.is_empty() {
        return Err(NotTouch::new("the report descriptor is empty"));
    }
    if desc.len() > MAX_DESCRIPTOR_BYTES {
        return Err(NotTouch::new(format!(
            "the report descriptor has {} bytes, more than the {MAX_DESCRIPTOR_BYTES} HID allows",
            desc.len()
        )));
    }
    let items = ReportDescriptorItems::try_from(desc).map_err(|e| parse_error(&e, |o| o))?;
    // Usage Page (0) first: a page-less Usage then gets page 0, as in the kernel,
    // instead of hidreport's `expect`.
    let prefix = [0x05u8, 0x00];
    let mut out = Vec::with_capacity(desc.len() + prefix.len() + 16);
    out.extend_from_slice(&prefix);
    let mut shifts = vec![(0usize, prefix.len())];
    let mut globals = vec![ScanGlobals::default()];
    let mut locals = vec![ScanLocals::default()];
    let mut open: Vec<u64> = Vec::new();
    let mut open_cost: u64 = 0;
    let mut cost: u64 = 0;
    let mut total_bits: u64 = 0;
    let mut copied_to = 0usize;
    let too_complex = |offset: usize| {
        NotTouch::new(format!(
            "unparsable report descriptor at byte {offset}: it declares more fields, \
             usages or nesting than a device can have"
        ))
    };
    for it in items.iter() {
        let offset = it.offset();
        let item = it.item();
        let raw = item.bytes();
        let (Some(g), Some(l)) = (globals.last().copied(), locals.last().copied()) else {
            break;
        };
        let mut replacement = None;
        match item.item_type() {
            ItemType::Main(main) => match main {
                MainItem::Collection(_) => {
                    let n = l.compiled();
                    if n > MAX_USAGE_RANGE {
                        return Err(usage_range_error(offset, n));
                    }
                    let c = 48 + 4 * n;
                    cost = cost.saturating_add(c);
                    open.push(c);
                    open_cost = open_cost.saturating_add(c);
                    reset_top(&mut locals);
                }
                MainItem::EndCollection => {
                    let Some(c) = open.pop() else {
                        // hidreport refuses the descriptor here.
                        break;
                    };
                    open_cost = open_cost.saturating_sub(c);
                    reset_top(&mut locals);
                }
                MainItem::Input(_) | MainItem::Output(_) | MainItem::Feature(_) => {
                    if g.report_size > 0 && g.report_count > 0 {
                        if g.report_size > MAX_REPORT_SIZE_BITS {
                            return Err(NotTouch::new(format!(
                                "unparsable report descriptor at byte {offset}: Report Size {} \
                                 bits is more than the {MAX_REPORT_SIZE_BITS} allowed",
                                g.report_size
                            )));
                        }
                        if g.report_count > MAX_REPORT_COUNT {
                            return Err(NotTouch::new(format!(
                                "unparsable report descriptor at byte {offset}: Report Count {} \
                                 is more than the {MAX_REPORT_COUNT} allowed",
                                g.report_count
                            )));
                        }
                        total_bits += g.report_size * g.report_count;
                        if total_bits > MAX_TOTAL_BITS {
                            return Err(too_complex(offset));
                        }
                        let flags = raw.get(1).copied().unwrap_or(0);
                        let constant = flags & 1 != 0;
                        let variable = flags & 2 != 0;
                        if constant {
                            cost = cost.saturating_add(64);
                        } else {
                            let n = l.compiled();
                            if n > MAX_USAGE_RANGE {
                                return Err(usage_range_error(offset, n));
                            }
                            let per_field = 200u64.saturating_add(open_cost);
                            let fields = if variable { g.report_count } else { 1 };
                            cost = cost
                                .saturating_add(4 * n)
                                .saturating_add(fields.saturating_mul(per_field));
                        }
                    }
                    reset_top(&mut locals);
                }
            },
            ItemType::Global(global) => {
                let Some(top) = globals.last_mut() else {
                    break;
                };
                match global {
                    GlobalItem::LogicalMinimum(v) => top.logical_min_negative = i32::from(v) < 0,
                    GlobalItem::PhysicalMinimum(v) => top.physical_min_negative = i32::from(v) < 0,
                    GlobalItem::LogicalMaximum(_) if !g.logical_min_negative => {
                        replacement = widen_maximum(raw);
                    }
                    GlobalItem::PhysicalMaximum(_) if !g.physical_min_negative => {
                        replacement = widen_maximum(raw);
                    }
                    GlobalItem::ReportSize(v) => top.report_size = usize::from(v) as u64,
                    GlobalItem::ReportCount(v) => top.report_count = usize::from(v) as u64,
                    GlobalItem::Push => {
                        globals.push(g);
                        locals.push(l);
                        cost = cost.saturating_add(64 + 8 * l.usages);
                    }
                    GlobalItem::Pop => {
                        if globals.len() <= 1 {
                            // hidreport refuses the descriptor here.
                            break;
                        }
                        globals.pop();
                        locals.pop();
                    }
                    _ => {}
                }
            }
            ItemType::Local(local) => {
                let Some(top) = locals.last_mut() else {
                    break;
                };
                match local {
                    LocalItem::Usage(..) | LocalItem::UsageId(_) => {
                        top.usages += 1;
                        cost = cost.saturating_add(8);
                    }
                    LocalItem::UsageMinimum(v) => top.usage_min = Some(u32::from(v)),
                    LocalItem::UsageMaximum(v) => top.usage_max = Some(u32::from(v)),
                    _ => {}
                }
            }
            ItemType::Long | ItemType::Reserved => {}
        }
        if cost > MAX_PARSE_COST_BYTES {
            return Err(too_complex(offset));
        }
        if let Some(new) = replacement {
            out.extend_from_slice(&desc[copied_to..offset]);
            out.extend_from_slice(&new);
            copied_to = offset + raw.len();
            let grown = new.len() - raw.len();
            let shift = shifts.last().map_or(0, |s| s.1) + grown;
            shifts.push((out.len(), shift));
        }
    }
    out.extend_from_slice(desc.get(copied_to..).unwrap_or(&[]));
    Ok(Normalised { bytes: out, shifts })
}

fn reset_top(locals: &mut [ScanLocals]) {
    if let Some(top) = locals.last_mut() {
        *top = ScanLocals::default();
    }
}

fn usage_range_error(offset: usize, n: u64) -> NotTouch {
    NotTouch::new(format!(
        "unparsable report descriptor at byte {offset}: a Usage Minimum/Maximum range of \
         {n} usages (at most {MAX_USAGE_RANGE} accepted)"
    ))
}

pub(super) fn parse_error(e: &hidreport::ParserError, map: impl Fn(usize) -> usize) -> NotTouch {
    match e {
        hidreport::ParserError::InvalidData { offset, message } => NotTouch::new(format!(
            "unparsable report descriptor at byte {}: {message}",
            map(*offset)
        )),
        other => NotTouch::new(format!("unparsable report descriptor: {other}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widen_unsigned_maxima() {
        assert_eq!(widen_maximum(&[0x25, 0xff]), Some(vec![0x26, 0xff, 0x00]));
        assert_eq!(
            widen_maximum(&[0x26, 0xff, 0xff]),
            Some(vec![0x27, 0xff, 0xff, 0, 0])
        );
        assert_eq!(widen_maximum(&[0x25, 0x7f]), None);
        assert_eq!(widen_maximum(&[0x27, 0xff, 0xff, 0xff, 0xff]), None);
    }
}

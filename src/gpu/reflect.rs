//! Just enough SPIR-V reading to check that host structs and shader blocks agree: member
//! offsets of a named block and the specialization-constant ids a shader declares.

use std::collections::HashMap;

const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_SPEC_ID: u32 = 1;
const DECORATION_OFFSET: u32 = 35;

fn words(spirv: &[u8]) -> Vec<u32> {
    spirv
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn string(ws: &[u32]) -> String {
    let bytes: Vec<u8> = ws
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Instructions as (opcode, operands).
fn instructions(spirv: &[u8]) -> Vec<(u32, Vec<u32>)> {
    let ws = words(spirv);
    let mut out = Vec::new();
    let mut i = 5;
    while i < ws.len() {
        let count = (ws[i] >> 16) as usize;
        let op = ws[i] & 0xffff;
        if count == 0 || i + count > ws.len() {
            break;
        }
        out.push((op, ws[i + 1..i + count].to_vec()));
        i += count;
    }
    out
}

/// The workgroup size a compute module declares (`layout(local_size_x = …)`, the
/// `LocalSize` execution mode), if it declares one.
pub fn local_size(spirv: &[u8]) -> Option<[u32; 3]> {
    const OP_EXECUTION_MODE: u32 = 16;
    const LOCAL_SIZE: u32 = 17;
    instructions(spirv).into_iter().find_map(|(op, a)| {
        (op == OP_EXECUTION_MODE && a.len() == 5 && a[1] == LOCAL_SIZE).then(|| [a[2], a[3], a[4]])
    })
}

/// `(member name, byte offset)` of the struct (block) type named `type_name`, in member order.
/// A struct that a block holds and a shader also copies into a private variable is two types
/// of one name, one of them without offsets: the one with offsets is the block's.
pub fn member_offsets(spirv: &[u8], type_name: &str) -> Option<Vec<(String, u32)>> {
    let ins = instructions(spirv);
    let named: Vec<u32> = ins
        .iter()
        .filter(|(op, a)| *op == OP_NAME && a.len() > 1 && string(&a[1..]) == type_name)
        .map(|(_, a)| a[0])
        .collect();
    let laid_out = |id: u32| {
        ins.iter().any(|(op, a)| {
            *op == OP_MEMBER_DECORATE && a[0] == id && a.get(2) == Some(&DECORATION_OFFSET)
        })
    };
    let id = named
        .iter()
        .copied()
        .find(|&id| laid_out(id))
        .or_else(|| named.first().copied())?;
    let mut names: HashMap<u32, String> = HashMap::new();
    let mut offsets: HashMap<u32, u32> = HashMap::new();
    for (op, a) in &ins {
        if *op == OP_MEMBER_NAME && a[0] == id {
            names.insert(a[1], string(&a[2..]));
        }
        if *op == OP_MEMBER_DECORATE && a[0] == id && a.get(2) == Some(&DECORATION_OFFSET) {
            offsets.insert(a[1], a[3]);
        }
    }
    let mut members: Vec<(u32, String, u32)> = offsets
        .iter()
        .map(|(m, off)| (*m, names.get(m).cloned().unwrap_or_default(), *off))
        .collect();
    members.sort();
    Some(members.into_iter().map(|(_, n, o)| (n, o)).collect())
}

/// `(constant name, SpecId)` of every specialization constant the module declares.
pub fn spec_constants(spirv: &[u8]) -> Vec<(String, u32)> {
    let ins = instructions(spirv);
    let names: HashMap<u32, String> = ins
        .iter()
        .filter(|(op, a)| *op == OP_NAME && a.len() > 1)
        .map(|(_, a)| (a[0], string(&a[1..])))
        .collect();
    let mut out: Vec<(String, u32)> = ins
        .iter()
        .filter(|(op, a)| *op == OP_DECORATE && a.get(1) == Some(&DECORATION_SPEC_ID))
        .map(|(_, a)| (names.get(&a[0]).cloned().unwrap_or_default(), a[2]))
        .collect();
    out.sort_by_key(|(_, id)| *id);
    out
}

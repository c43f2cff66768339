//! Each error that names a parameter, worded in both terms: the sentences the CLI and Python
//! have always printed, byte for byte.

use super::*;

/// `e` worded on the command line and in Python.
fn both(e: &Error) -> [String; 2] {
    [e.in_terms(Terms::Flags), e.in_terms(Terms::Keywords)]
}

fn too_large(machine: bool, disk: bool) -> Error {
    Error::TooLarge {
        path: "ct.nii.gz".into(),
        what: "a 8x8x8 f32 volume".into(),
        needed: 2048,
        limit: 1024,
        machine,
        disk,
    }
}

#[test]
fn parameters_are_named_by_flag_or_keyword() {
    let e = Error::invalid("ray_spacing", 0, "a positive number of mm");
    assert_eq!(
        both(&e),
        [
            "--ray-spacing 0: expected a positive number of mm",
            "ray_spacing=0: expected a positive number of mm"
        ]
    );
    let e = Error::invalid("type", "u7", "one of u8");
    assert_eq!(
        both(&e),
        [
            "--type u7: expected one of u8",
            "dtype=u7: expected one of u8"
        ]
    );
    let e = Error::invalid("nameless", 1, "2");
    assert_eq!(
        both(&e),
        ["nameless 1: expected 2", "nameless=1: expected 2"]
    );
    let e = Error::DefaultUnfit {
        parameter: "slabs",
        value: "4".into(),
        expected: "2 to 3".into(),
    };
    assert_eq!(
        both(&e),
        [
            "the default of 4 slabs does not fit: 2 to 3 (--slabs K asks for another)",
            "the default of 4 slabs does not fit: 2 to 3 (slabs=K asks for another)"
        ]
    );
}

#[test]
fn values_are_written_in_each_syntax() {
    let unfit = |value| Error::Unfit {
        parameter: "size",
        value,
        problem: "too small".into(),
    };
    assert_eq!(
        both(&unfit(Value::Size(30, 20))),
        ["--size 30x20: too small", "size=(30, 20): too small"]
    );
    assert_eq!(
        both(&unfit(Value::Whole(5))),
        ["--size 5: too small", "size=5: too small"]
    );
    let e = Error::Conflicting {
        parameters: ["slabs", "threshold"],
    };
    assert_eq!(
        both(&e),
        [
            "--slabs and --threshold cannot both be given",
            "slabs= and threshold= cannot both be given"
        ]
    );
    let e = Error::Needs {
        parameter: "solo",
        needed: "highlight",
    };
    assert_eq!(
        both(&e),
        ["--solo needs --highlight", "solo= needs highlight= too"]
    );
}

#[test]
fn limits_say_what_lifts_them() {
    let said = "ct.nii.gz: a 8x8x8 f32 volume needs 2.0 KiB (2048 bytes), over the memory limit \
                of 1.0 KiB (1024 bytes)";
    assert_eq!(
        both(&too_large(false, false)),
        [
            format!("{said} (raise it with --max-memory)"),
            format!("{said} (raise it with max_memory=)")
        ]
    );
    assert_eq!(
        both(&too_large(false, true)),
        [
            format!("{said} (raise it with --max-memory, or decode it to disk with --scratch DIR)"),
            format!("{said} (raise it with max_memory=, or decode it to disk with scratch=)")
        ]
    );
    assert_eq!(
        both(&too_large(true, true)),
        [
            format!("{said} (decode it to disk with --scratch DIR)"),
            format!("{said} (decode it to disk with scratch=)")
        ]
    );
    assert_eq!(both(&too_large(true, false)), [said, said]);
    let e = Error::TooCoarse {
        note: "the budget chose level 2".into(),
        cause: Box::new(Error::invalid("slabs", 4, "2 to 3")),
    };
    assert_eq!(
        both(&e),
        [
            "--slabs 4: expected 2 to 3, because the budget chose level 2 (raise it with \
             --max-memory)",
            "slabs=4: expected 2 to 3, because the budget chose level 2 (raise it with \
             max_memory=)"
        ]
    );
}

#[test]
fn files_say_what_to_give() {
    let e = Error::RawUndescribed {
        path: "scan.raw".into(),
        missing: &["dims", "type"],
        detail: "headerless data".into(),
    };
    assert_eq!(
        both(&e),
        [
            "scan.raw: headerless data: give --dims NXxNYxNZ and --type (one of u8, i8, u16, \
             i16, u32, i32, f32, f64)",
            "scan.raw: headerless data: give dims=(NX, NY, NZ) and dtype= (one of u8, i8, u16, \
             i16, u32, i32, f32, f64)"
        ]
    );
    let e = Error::Exists {
        path: "out.png".into(),
    };
    assert_eq!(
        both(&e),
        [
            "out.png: already exists (use --force to overwrite it)",
            "out.png: already exists (force=True overwrites it)"
        ]
    );
    let e = Error::NotRegularFile {
        path: "fifo".into(),
    };
    let said = "fifo: not a regular file: slabscope writes only regular files";
    assert_eq!(both(&e), [format!("{said}, --force or not"), said.into()]);
    let series = |localizers| Error::Series {
        path: "dir".into(),
        message: "2 series".into(),
        localizers,
    };
    assert_eq!(
        both(&series(false)),
        [
            "dir: 2 series (pick one with --series N|UID)",
            "dir: 2 series (pick one with series=N or series=UID)"
        ]
    );
    assert_eq!(
        both(&series(true)),
        [
            "dir: 2 series (--include-localizers keeps them)",
            "dir: 2 series (include_localizers=True keeps them)"
        ]
    );
}

#[test]
fn other_errors_read_as_they_display() {
    let e = Error::Truncated {
        path: "a.nrrd".into(),
        expected: 10,
        found: 4,
    };
    let said = "a.nrrd: truncated voxel data: expected 10 bytes, found 4";
    assert_eq!(both(&e), [said, said]);
    assert_eq!(both(&Error::Cancelled), ["cancelled", "cancelled"]);
}

#[test]
fn placeholders_of_several_numbers_are_tuples() {
    assert_eq!(tuple("NXxNYxNZ"), "(NX, NY, NZ)");
    assert_eq!(tuple("SX,SY,SZ"), "(SX, SY, SZ)");
    assert_eq!(tuple("WxH"), "(W, H)");
    for kept in ["K", "N", "x", "DIR", "BYTES", "xyz"] {
        assert_eq!(tuple(kept), kept);
    }
}

/// In a list whose line names the file (triage's rows), an error about that file reads without
/// it, one about another file (or none) whole: told by the error's path, not its words.
#[test]
fn errors_of_a_listed_file_leave_its_name_out() {
    let raw = Error::RawUndescribed {
        path: "scan.raw".into(),
        missing: &["dims"],
        detail: "headerless data".into(),
    };
    let e = too_large(false, false);
    let file = std::path::Path::new("ct.nii.gz");
    let said = "a 8x8x8 f32 volume needs 2.0 KiB (2048 bytes), over the memory limit of 1.0 KiB \
                (1024 bytes)";
    assert_eq!(e.detail(), said);
    assert_eq!(e.within(file), said);
    assert_eq!(e.to_string(), format!("ct.nii.gz: {said}"));
    assert_eq!(
        e.in_terms_within(Terms::Flags, file),
        format!("{said} (raise it with --max-memory)")
    );
    assert_eq!(
        e.in_terms_within(Terms::Keywords, file),
        format!("{said} (raise it with max_memory=)")
    );
    assert_eq!(
        raw.in_terms_within(Terms::Flags, std::path::Path::new("scan.raw")),
        "headerless data: give --dims NXxNYxNZ"
    );
    for terms in [Terms::Flags, Terms::Keywords] {
        assert_eq!(raw.in_terms_within(terms, file), raw.in_terms(terms));
        let bins = Error::invalid("bins", 1, "2 to 255");
        assert_eq!(bins.in_terms_within(terms, file), bins.in_terms(terms));
    }
    assert_eq!(raw.within(file), raw.to_string());
    // A file's error reached from the one named keeps both names, the named first.
    let reached = raw.reached_from(std::path::Path::new("scan.nhdr"));
    assert_eq!(
        reached.to_string(),
        "scan.nhdr: scan.raw: headerless data: its dims must be given"
    );
}

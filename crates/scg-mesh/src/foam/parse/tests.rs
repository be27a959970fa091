//! Tests of [`super`] (parse).

use super::*;

fn parser(s: &[u8]) -> Parser<'_> {
    Parser::new(Path::new("test"), s)
}

#[test]
fn comments_and_dictionaries() {
    let src = b"/* c */ a 1; // x\n b { c (1 2 3); d \"q;s\"; } e [0 1 -1 0 0 0 0];";
    let d = parser(src).dict_body("", false).unwrap();
    assert_eq!(d.number("a"), Some(1.0));
    let Some(Value::Dict(b)) = d.get("b") else {
        panic!("b is a dict")
    };
    assert_eq!(b.word("d"), Some("q;s"));
    assert_eq!(
        b.get("c"),
        Some(&Value::Tokens(vec![
            Token::Punct(b'('),
            Token::Num(1.0),
            Token::Num(2.0),
            Token::Num(3.0),
            Token::Punct(b')')
        ]))
    );
}

#[test]
fn lists_ascii_uniform_binary() {
    assert_eq!(parser(b"3(1 2 3)").list("l", LABEL).unwrap(), vec![1, 2, 3]);
    assert_eq!(parser(b"3{7}").list("l", LABEL).unwrap(), vec![7, 7, 7]);
    assert_eq!(
        parser(b"2{(1 2 3)}").list("l", VECTOR).unwrap(),
        vec![DVec3::new(1.0, 2.0, 3.0); 2]
    );
    let mut bytes = b"2\n(".to_vec();
    bytes.extend(5i32.to_le_bytes());
    bytes.extend((-1i32).to_le_bytes());
    bytes.push(b')');
    let mut p = parser(&bytes);
    p.enc.binary = true;
    assert_eq!(p.list("l", LABEL).unwrap(), vec![5, -1]);
    let mut bytes = b"1(".to_vec();
    for x in [1.5f32, -2.0, 3.25] {
        bytes.extend(x.to_be_bytes());
    }
    bytes.push(b')');
    let mut p = parser(&bytes);
    p.enc = Encoding {
        binary: true,
        label64: true,
        scalar32: true,
        big_endian: true,
    };
    assert_eq!(
        p.list("l", VECTOR).unwrap(),
        vec![DVec3::new(1.5, -2.0, 3.25)]
    );
}

#[test]
fn word_and_tensor_lists() {
    let src = b"inGroups List<word> 1(wall); R nonuniform List<symmTensor> 2((1 2 3 4 5 6) (1 2 3 4 5 6)); nFaces 3;";
    let d = parser(src).dict_body("", false).unwrap();
    assert_eq!(d.number("nFaces"), Some(3.0));
    assert_eq!(
        d.get("R"),
        Some(&Value::Tokens(vec![
            Token::Word("nonuniform".into()),
            Token::List(ListData::Tuples(6, 2))
        ]))
    );
    let mut bytes = b"T nonuniform List<tensor> 1(".to_vec();
    for x in 0..9 {
        bytes.extend((x as f64).to_le_bytes());
    }
    bytes.extend(b"); g List<word> 2(a b);");
    let mut p = parser(&bytes);
    p.enc.binary = true;
    let d = p.dict_body("", false).unwrap();
    assert!(
        matches!(d.get("T"), Some(Value::Tokens(t)) if t[1] == Token::List(ListData::Tuples(9, 1)))
    );
    assert!(matches!(d.get("g"), Some(Value::Tokens(t)) if t.len() == 6));
}

#[test]
fn errors_name_the_entry() {
    let e = parser(b"3(1 2").list("owner", LABEL).unwrap_err();
    assert!(e.to_string().contains("owner[2]"), "{e}");
    let e = parser(b"a uniform $x;").dict_body("", false).unwrap_err();
    assert!(e.to_string().contains("$x"), "{e}");
    let e = parser(b"2(1.0 x)").list("p", SCALAR).unwrap_err();
    assert!(
        e.to_string().contains("p[1]") && e.to_string().contains("'x'"),
        "{e}"
    );
}

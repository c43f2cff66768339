//! AWS Signature Version 4 for the GETs and HEADs of an `s3://` store, when the environment
//! holds credentials (`AWS_ACCESS_KEY_ID` and `AWS_SECRET_ACCESS_KEY`, with
//! `AWS_SESSION_TOKEN` when set): each request is signed with its time, the payload unsigned
//! (`UNSIGNED-PAYLOAD`, as S3 allows), and the signed headers `host`, `x-amz-content-sha256`,
//! `x-amz-date` (and `x-amz-security-token`). Tested against AWS's published example. The secret
//! is never shown: the credentials' `Debug` leaves it out, and no message names it.

use std::fmt::Write as _;

use sha2::{Digest, Sha256};

/// Credentials from the environment.
#[derive(Clone)]
pub struct Credentials {
    key_id: String,
    secret: String,
    token: Option<String>,
}

impl std::fmt::Debug for Credentials {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Credentials(..)")
    }
}

impl Credentials {
    /// The credentials `env` (the environment) holds: both a key id and a secret, else none
    /// (the store is then read anonymously).
    pub fn from_env(env: impl Fn(&str) -> Option<String>) -> Option<Self> {
        let set = |name: &str| env(name).filter(|v| !v.trim().is_empty());
        Some(Self {
            key_id: set("AWS_ACCESS_KEY_ID")?,
            secret: set("AWS_SECRET_ACCESS_KEY")?,
            token: set("AWS_SESSION_TOKEN"),
        })
    }
}

/// The hexadecimal of `bytes`, lower case.
fn hex(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        let _ = write!(out, "{b:02x}");
    }
    out
}

/// HMAC-SHA256 of `message` under `key` (RFC 2104).
fn hmac(key: &[u8], message: &[u8]) -> [u8; 32] {
    let mut block = [0u8; 64];
    if key.len() > 64 {
        block[..32].copy_from_slice(&Sha256::digest(key));
    } else {
        block[..key.len()].copy_from_slice(key);
    }
    let pad = |byte: u8| block.map(|b| b ^ byte);
    let inner = Sha256::new()
        .chain_update(pad(0x36))
        .chain_update(message)
        .finalize();
    Sha256::new()
        .chain_update(pad(0x5c))
        .chain_update(inner)
        .finalize()
        .into()
}

/// The signing key of `secret` for the day `date` (`YYYYMMDD`), `region` and `service`.
fn signing_key(secret: &str, date: &str, region: &str, service: &str) -> [u8; 32] {
    let k = hmac(format!("AWS4{secret}").as_bytes(), date.as_bytes());
    let k = hmac(&k, region.as_bytes());
    let k = hmac(&k, service.as_bytes());
    hmac(&k, b"aws4_request")
}

/// One request to sign: its method, path (percent-encoded, as sent), query, headers (lower-case
/// names, each signed), the SHA-256 of its payload (or `UNSIGNED-PAYLOAD`), its time
/// (`YYYYMMDDTHHMMSSZ`), region and service.
struct Request<'a> {
    method: &'a str,
    path: &'a str,
    query: &'a str,
    headers: &'a [(&'a str, &'a str)],
    payload: &'a str,
    time: &'a str,
    region: &'a str,
    service: &'a str,
}

impl Request<'_> {
    /// The `Authorization` header's value for `creds`.
    fn authorization(&self, creds: &Credentials) -> String {
        let mut headers: Vec<(&str, &str)> = self.headers.to_vec();
        headers.sort_unstable();
        let canonical: String = headers.iter().fold(String::new(), |mut s, (n, v)| {
            let _ = writeln!(s, "{n}:{}", v.trim());
            s
        });
        let signed: Vec<&str> = headers.iter().map(|(n, _)| *n).collect();
        let signed = signed.join(";");
        let path = if self.path.is_empty() { "/" } else { self.path };
        let request = format!(
            "{}\n{path}\n{}\n{canonical}\n{signed}\n{}",
            self.method, self.query, self.payload
        );
        let date = &self.time[..8];
        let scope = format!("{date}/{}/{}/aws4_request", self.region, self.service);
        let to_sign = format!(
            "AWS4-HMAC-SHA256\n{}\n{scope}\n{}",
            self.time,
            hex(&Sha256::digest(request.as_bytes()))
        );
        let key = signing_key(&creds.secret, date, self.region, self.service);
        let signature = hex(&hmac(&key, to_sign.as_bytes()));
        format!(
            "AWS4-HMAC-SHA256 Credential={}/{scope}, SignedHeaders={signed}, Signature={signature}",
            creds.key_id
        )
    }
}

/// The headers of a signed S3 `method` of `path` (percent-encoded) at `host` in `region`, made
/// at the time `now` (seconds since 1970): to add to the request.
pub fn s3_headers(
    creds: &Credentials,
    method: &str,
    host: &str,
    path: &str,
    region: &str,
    now: u64,
) -> Vec<(&'static str, String)> {
    let time = amz_time(now);
    let payload = "UNSIGNED-PAYLOAD";
    let mut headers = vec![
        ("host", host),
        ("x-amz-content-sha256", payload),
        ("x-amz-date", time.as_str()),
    ];
    if let Some(token) = &creds.token {
        headers.push(("x-amz-security-token", token.as_str()));
    }
    let authorization = Request {
        method,
        path,
        query: "",
        headers: &headers,
        payload,
        time: &time,
        region,
        service: "s3",
    }
    .authorization(creds);
    let mut out = vec![
        ("x-amz-content-sha256", payload.to_string()),
        ("x-amz-date", time.clone()),
        ("authorization", authorization),
    ];
    if let Some(token) = &creds.token {
        out.push(("x-amz-security-token", token.clone()));
    }
    out
}

/// `YYYYMMDDTHHMMSSZ` of `secs` seconds since 1970 (UTC).
fn amz_time(secs: u64) -> String {
    let (days, rest) = (secs / 86_400, secs % 86_400);
    // Howard Hinnant's civil_from_days.
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const SECRET: &str = "wJalrXUtnFEMI/K7MDENG+bPxRfiCYEXAMPLEKEY";

    #[test]
    fn signatures_are_awss_published_example() {
        // AWS's "Signature Version 4 signing process" example (IAM ListUsers, 2015-08-30).
        let key = signing_key(SECRET, "20150830", "us-east-1", "iam");
        assert_eq!(
            hex(&key),
            "c4afb1cc5771d871763a393e44b703571b55cc28424d1a5e86da6ed3c154a4b9"
        );
        let creds = Credentials::from_env(|n| match n {
            "AWS_ACCESS_KEY_ID" => Some("AKIDEXAMPLE".into()),
            "AWS_SECRET_ACCESS_KEY" => Some(SECRET.into()),
            _ => None,
        })
        .unwrap();
        let request = Request {
            method: "GET",
            path: "/",
            query: "Action=ListUsers&Version=2010-05-08",
            headers: &[
                ("host", "iam.amazonaws.com"),
                (
                    "content-type",
                    "application/x-www-form-urlencoded; charset=utf-8",
                ),
                ("x-amz-date", "20150830T123600Z"),
            ],
            payload: &hex(&Sha256::digest(b"")),
            time: "20150830T123600Z",
            region: "us-east-1",
            service: "iam",
        };
        assert_eq!(
            request.authorization(&creds),
            "AWS4-HMAC-SHA256 Credential=AKIDEXAMPLE/20150830/us-east-1/iam/aws4_request, \
             SignedHeaders=content-type;host;x-amz-date, \
             Signature=5d672d79c15b13162d9279b0855cfba6789a8edb4c82c400e06b5924a6f2b5d7"
        );
        // The secret is never shown.
        assert!(!format!("{creds:?}").contains("EXAMPLEKEY"));
        // HMAC-SHA256 against RFC 4231's test case 2.
        assert_eq!(
            hex(&hmac(b"Jefe", b"what do ya want for nothing?")),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843"
        );
    }

    #[test]
    fn s3_requests_carry_the_signed_headers() {
        assert_eq!(amz_time(1_440_938_160), "20150830T123600Z");
        assert_eq!(amz_time(951_782_400), "20000229T000000Z");
        let none = |_: &str| None;
        assert!(Credentials::from_env(none).is_none());
        let creds = Credentials {
            key_id: "AKID".into(),
            secret: SECRET.into(),
            token: Some("TOKEN".into()),
        };
        let headers = s3_headers(
            &creds,
            "GET",
            "b.s3.eu-west-2.amazonaws.com",
            "/a/0",
            "eu-west-2",
            1_440_938_160,
        );
        let names: Vec<&str> = headers.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names,
            [
                "x-amz-content-sha256",
                "x-amz-date",
                "authorization",
                "x-amz-security-token"
            ]
        );
        let auth = &headers[2].1;
        assert!(
            auth.starts_with(
                "AWS4-HMAC-SHA256 Credential=AKID/20150830/eu-west-2/s3/aws4_request, \
             SignedHeaders=host;x-amz-content-sha256;x-amz-date;x-amz-security-token, Signature="
            ),
            "{auth}"
        );
        assert!(!auth.contains("EXAMPLEKEY"));
    }
}

#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| plie_fuzz::plie(data));

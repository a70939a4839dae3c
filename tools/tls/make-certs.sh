#!/usr/bin/env bash
# Certificates for Modbus/TCP Security (homingd --tls, homingctl --tls), made
# with the openssl command line: a CA, the module's certificate and one client
# certificate per role, the role in the extension 1.3.6.1.4.1.50316.802.1
# (an ASN.1 UTF8String). For commissioning and for the tests.
#
#   make-certs.sh init DIR [--server-ip IP]... [--server-dns NAME]... [--org NAME] [--days N] [--test-set]
#       DIR/ca.crt ca.key       the CA: homingd --tls-ca, homingctl --ca, pymodbus' cafile
#       DIR/server.crt .key     the module: homingd --tls-cert --tls-key (names IP 127.0.0.1
#                               and DNS localhost unless --server-ip/--server-dns are given)
#       DIR/engineer.crt .key   one client per role: homingctl --cert --key
#       DIR/operator.crt .key
#       DIR/viewer.crt .key
#       DIR/crl.pem             the revocation list: homingd --tls-crl
#     --test-set adds what the tests refuse or treat specially: no-role (no role
#     extension), unknown-role (role "admin"), expired, not-yet-valid, revoked
#     (in crl.pem), and other-ca-engineer, signed by a second CA (DIR/other-ca/).
#   make-certs.sh client DIR NAME ROLE [--days N]   another client: DIR/NAME.crt .key
#   make-certs.sh revoke DIR NAME                   revoke DIR/NAME.crt and rewrite DIR/crl.pem
#   make-certs.sh crl DIR                           rewrite DIR/crl.pem (before its next update)
#
# Keys are EC P-256, written readable by their owner only. Keep ca.key off the
# module: it signs every certificate the module trusts.
set -euo pipefail

readonly ROLE_OID=1.3.6.1.4.1.50316.802.1
openssl_q() { openssl "$@" 2>/dev/null; }
die() { echo "make-certs.sh: $*" >&2; exit 2; }

# The openssl ca configuration and database of the CA in $1.
ca_config() {
  local dir=$1
  cat >"$dir/ca-db/openssl.cnf" <<CNF
[ ca ]
default_ca = module_ca
[ module_ca ]
database = $dir/ca-db/index.txt
new_certs_dir = $dir/ca-db/issued
serial = $dir/ca-db/serial
crlnumber = $dir/ca-db/crlnumber
certificate = $dir/ca.crt
private_key = $dir/ca.key
default_md = sha256
default_days = 825
default_crl_days = 365
policy = any_name
unique_subject = no
copy_extensions = none
email_in_dn = no
[ any_name ]
organizationName = optional
commonName = supplied
CNF
}

new_key() {
  (umask 077 && openssl_q genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1")
}

# make_ca DIR COMMON_NAME ORG DAYS
make_ca() {
  local dir=$1 cn=$2 org=$3 days=$4
  mkdir -p "$dir/ca-db/issued"
  : >"$dir/ca-db/index.txt"
  echo 1000 >"$dir/ca-db/serial"
  echo 1000 >"$dir/ca-db/crlnumber"
  new_key "$dir/ca.key"
  openssl_q req -x509 -new -key "$dir/ca.key" -subj "/O=$org/CN=$cn" -days "$days" -sha256 \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign" \
    -addext "subjectKeyIdentifier=hash" -out "$dir/ca.crt"
  ca_config "$dir"
}

# issue CA_DIR OUT_DIR NAME SUBJECT EXTENSIONS [openssl ca date options...]
issue() {
  local ca=$1 out=$2 name=$3 subject=$4 extensions=$5
  shift 5
  local ext
  ext=$(mktemp)
  printf '[ext]\nbasicConstraints = critical,CA:FALSE\nkeyUsage = critical,digitalSignature\nsubjectKeyIdentifier = hash\nauthorityKeyIdentifier = keyid\n%b\n' \
    "$extensions" >"$ext"
  new_key "$out/$name.key"
  openssl_q req -new -key "$out/$name.key" -subj "$subject" -out "$out/$name.csr"
  if ! openssl ca -batch -notext -config "$ca/ca-db/openssl.cnf" -in "$out/$name.csr" -out "$out/$name.crt" \
      -extfile "$ext" -extensions ext "$@" 2>"$out/$name.log"; then
    cat "$out/$name.log" >&2
    rm -f "$ext"
    die "openssl ca could not sign $name"
  fi
  rm -f "$ext" "$out/$name.csr" "$out/$name.log"
}

# client CA_DIR OUT_DIR NAME ORG ROLE|"" [date options]
client() {
  local ca=$1 out=$2 name=$3 org=$4 role=$5
  shift 5
  local ext="extendedKeyUsage = clientAuth"
  [ -n "$role" ] && ext+="\n$ROLE_OID = ASN1:UTF8String:$role"
  issue "$ca" "$out" "$name" "/O=$org/CN=$name" "$ext" "$@"
}

write_crl() {
  openssl_q ca -gencrl -config "$1/ca-db/openssl.cnf" -out "$1/crl.pem"
}

org_of() {  # the organisation of an existing CA
  openssl x509 -in "$1/ca.crt" -noout -subject -nameopt multiline | sed -n 's/^ *organizationName *= *//p'
}

init() {
  local dir="" days=825 org="Homing module" test_set=0
  local -a ips=() dns=()
  while [ $# -gt 0 ]; do
    case $1 in
      --server-ip) ips+=("$2"); shift 2 ;;
      --server-dns) dns+=("$2"); shift 2 ;;
      --org) org=$2; shift 2 ;;
      --days) days=$2; shift 2 ;;
      --test-set) test_set=1; shift ;;
      -*) die "unknown option $1" ;;
      *) [ -z "$dir" ] || die "one DIR only"; dir=$1; shift ;;
    esac
  done
  [ -n "$dir" ] || die "usage: make-certs.sh init DIR [options] (see the top of the script)"
  [ -e "$dir/ca.key" ] && die "$dir/ca.key exists: a second init would replace the CA every client trusts"
  [ ${#ips[@]} -eq 0 ] && [ ${#dns[@]} -eq 0 ] && ips=(127.0.0.1) && dns=(localhost)
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  local san="" entry
  for entry in "${ips[@]}"; do san+="${san:+,}IP:$entry"; done
  for entry in "${dns[@]}"; do san+="${san:+,}DNS:$entry"; done

  make_ca "$dir" "$org CA" "$org" 3650
  issue "$dir" "$dir" server "/O=$org/CN=homingd" "extendedKeyUsage = serverAuth\nsubjectAltName = $san" -days "$days"
  for role in engineer operator viewer; do client "$dir" "$dir" "$role" "$org" "$role" -days "$days"; done
  if [ $test_set -eq 1 ]; then
    client "$dir" "$dir" no-role "$org" "" -days "$days"
    client "$dir" "$dir" unknown-role "$org" admin -days "$days"
    client "$dir" "$dir" expired "$org" engineer -startdate 20200101000000Z -enddate 20210101000000Z
    client "$dir" "$dir" not-yet-valid "$org" engineer -startdate 20400101000000Z -enddate 20410101000000Z
    client "$dir" "$dir" revoked "$org" engineer -days "$days"
    openssl_q ca -config "$dir/ca-db/openssl.cnf" -revoke "$dir/revoked.crt"
    make_ca "$dir/other-ca" "Other CA" "Elsewhere" 3650
    client "$dir/other-ca" "$dir" other-ca-engineer "Elsewhere" engineer -days "$days"
  fi
  write_crl "$dir"
  echo "make-certs.sh: CA, server and role certificates in $dir"
}

case ${1:-} in
  init) shift; init "$@" ;;
  client)
    [ $# -ge 4 ] || die "usage: make-certs.sh client DIR NAME ROLE [--days N]"
    dir=$2 name=$3 role=$4 days=825
    [ "${5:-}" = --days ] && days=${6:?--days needs a number}
    [ -e "$dir/ca-db/openssl.cnf" ] || die "$dir has no CA made by make-certs.sh init"
    [ -e "$dir/$name.crt" ] && die "$dir/$name.crt exists"
    client "$dir" "$dir" "$name" "$(org_of "$dir")" "$role" -days "$days"
    echo "make-certs.sh: $dir/$name.crt (role $role)" ;;
  revoke)
    [ $# -eq 3 ] || die "usage: make-certs.sh revoke DIR NAME"
    openssl_q ca -config "$2/ca-db/openssl.cnf" -revoke "$2/$3.crt" || die "cannot revoke $2/$3.crt"
    write_crl "$2"
    echo "make-certs.sh: $3 revoked; give homingd the new $2/crl.pem (--tls-crl) and restart it" ;;
  crl)
    [ $# -eq 2 ] || die "usage: make-certs.sh crl DIR"
    write_crl "$2"
    echo "make-certs.sh: $2/crl.pem rewritten" ;;
  *) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2 ;;
esac

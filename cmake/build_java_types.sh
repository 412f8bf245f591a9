#!/bin/sh
# Compiles lcm-gen's Java sources into a jar for lcm-spy: build_java_types.sh JAVAC JAR SRC_DIR CLASSES_DIR OUT_JAR
set -e
javac=$1 jar=$2 src=$3 classes=$4 out=$5
rm -rf "$classes" && mkdir -p "$classes"
"$javac" -nowarn -cp /usr/share/java/lcm.jar -d "$classes" "$src"/sextant/*.java
"$jar" cf "$out" -C "$classes" .
